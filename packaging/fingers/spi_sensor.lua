-- spi_sensor.lua: a device model (docs/fingers.md) of a force sensor on the
-- finger's SPI. For 20 ms after power-on it answers zeros (starting up);
-- then every transfer answers 42 (ready), the force on the pad in
-- hundredths of a newton as a u16 LE, and zeros for the rest. 63h reads
-- the same 3 bytes (DATA_SIZE).
DATA_SIZE = 3
local started = dev.time()

local function reply(n)
  local out = {}
  if dev.time() - started >= 0.02 then
    local f = math.floor(dev.contact() * 100 + 0.5)
    if f > 65535 then f = 65535 end
    out[1] = string.char(42, f % 256, math.floor(f / 256))
  end
  local s = table.concat(out)
  if #s < n then s = s .. string.rep("\0", n - #s) end
  return s:sub(1, n)
end

function on_power(on)
  started = dev.time()
end

function on_spi(tx)
  return reply(#tx)
end

function data()
  return reply(3)
end
