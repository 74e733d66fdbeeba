-- tactile_tip.lua: a device model (docs/fingers.md) of a tactile fingertip
-- on the finger's UART, as wsgemu plays custom finger electronics. The tip
-- answers "z" with "x" (it is alive) and "a" with a frame of 5 x 5 taxels
-- at 2 mm, row by row, each a u16 LE: the force on it in mN, from the part's
-- contact patch on the pad (dev.contact()). 50 bytes take 4.3 ms at
-- 115200 baud.
local PITCH = 2.0

local function overlap(a0, a1, b0, b1)
  local lo, hi = math.max(a0, b0), math.min(a1, b1)
  if hi > lo then return hi - lo end
  return 0
end

local function frame()
  local force, x, y, w, h = dev.contact()
  local out = {}
  for r = 0, 4 do
    for c = 0, 4 do
      local cx, cy = (c - 2.5) * PITCH, (r - 2.5) * PITCH
      local v = 0
      if w * h > 0 then
        local a = overlap(cx, cx + PITCH, x - w / 2, x + w / 2) *
                  overlap(cy, cy + PITCH, y - h / 2, y + h / 2)
        v = math.floor(force * a / (w * h) * 1000 + 0.5)
      end
      if v > 65535 then v = 65535 end
      out[#out + 1] = string.char(v % 256, math.floor(v / 256))
    end
  end
  return table.concat(out)
end

function on_uart(bytes)
  for i = 1, #bytes do
    local b = bytes:sub(i, i)
    if b == "z" then
      dev.send("x")
    elseif b == "a" then
      dev.send(frame())
    end
  end
end
