-- api.lua: the script API on the wire, for integ_script. Each registered
-- ID B0h..BFh calls one part of the API (SCRIPTING.md) and answers what
-- it got, through wire.lua (required from beside this file); the test
-- compares the answers with what it sees over the command set and the
-- control channel. The script itself asserts nothing: a check that lived
-- here could not fail a test.
local wire = require "wire"
local socket = require "socket"

local h = {}

-- Echo: the payload as read, after E_SUCCESS (cmd.read's table, flattened
-- back by cmd.send).
h[0xB0] = function(id, p)
  cmd.send(id, etob(E_SUCCESS), p)
end

-- The command interface as the script sees it.
h[0xB1] = function(id)
  wire.reply(id, cmd.online(), cmd.available(), cmd.interface())
end

-- Sleep p[1] ms, inside pcall, then tell how many packets came meanwhile
-- and the clock: the wait must survive a protected call. Whether the
-- answer could be sent is kept for A0h.
local sleep_sent
h[0xB2] = function(id, p)
  local ok = pcall(sleep, p[1])
  sleep_sent = wire.reply(id, ok, cmd.available(), socket.gettime())
end

h[0xA0] = function(id)
  wire.reply(id, sleep_sent)
end

-- socket.sleep, in seconds: p[1] ms.
h[0xA1] = function(id, p)
  socket.sleep(p[1] / 1000)
  wire.reply(id, socket.gettime())
end

-- cmd.register (p[1] = 1) or cmd.unregister (2) of ID p[2].
h[0xB3] = function(id, p)
  if p[1] == 1 then
    wire.reply(id, pcall(cmd.register, p[2]))
  else
    wire.reply(id, cmd.unregister(p[2]))
  end
end

-- cmd.send's flattening: one packet with every kind of argument, then one
-- with what each bad argument raised.
h[0xB4] = function(id)
  cmd.send(id, etob(E_SUCCESS), 7, true, false, "AB", {1, {2, {3, {4}}}},
           ntob(1.5), {}, "")
  local function try(...)
    local ok, err = pcall(cmd.send, id, ...)
    return ok and "sent" or err
  end
  wire.reply(id, try(256), try(-1), try(1.5), try({{{{{{1}}}}}}), try(print),
             try(nil), try(string.rep("x", 65536)))
end

-- Conversions: ntob(bton(payload)) and fixed values as bytes, then the
-- readings as text.
-- A NaN is 0/0: the gripper's Lua has no math.nan.
h[0xB5] = function(id, p)
  local x = bton(p)
  local nan = 0 / 0
  cmd.send(id, etob(E_SUCCESS), ntob(x), etob(E_CMD_UNKNOWN), etob(0x1234),
           ntob(1.5), ntob(-2), ntob(nan))
  local short_ok, short_err = pcall(bton, {1, 2, 3})
  -- Called by name: Lua 5.2 names a function that pcall calls straight
  -- from a walk of the globals, 'etob' or '_G.etob' as the walk goes.
  local big_ok, big_err = pcall(function() return etob(65536) end)
  big_err = string.gsub(big_err, "^.-:%d+: ", "")
  wire.reply(id, x, short_ok, short_err, big_ok, big_err, math.nan == nil,
             type(nan), bton(ntob(nan)) ~= bton(ntob(nan)))
end

-- The status codes the script sees as globals, NAME=value, sorted.
h[0xB6] = function(id)
  local list = {}
  for k, v in pairs(_G) do
    if type(k) == "string" and k:match("^E_") then
      list[#list + 1] = k .. "=" .. wire.text(v)
    end
  end
  table.sort(list)
  wire.reply(id, table.concat(list, "|"))
end

-- print and printf, with the integer conversions of Lua 5.1 (2.7 as %d
-- prints 2, where Lua 5.4 would raise an error).
h[0xB7] = function(id)
  print("line", 1, 2.5, nil, true)
  printf("%d|%5.1f|%s|%x\n", 2.7, 3.14159, "s", 255.9)
  printf("%d%%\n", -2.7)
  wire.reply(id, string.format("%i", 7.9))
end

-- The names of Lua 5.1 and 5.2 that scripts of the gripper's era use.
h[0xB8] = function(id)
  local a, b, c = unpack({1, 2, 3})
  wire.reply(id, a + b + c, select("#", unpack({1, 2, 3})),
             table.getn({1, 2, 3}), math.pow(2, 10), loadstring("return 1 + 1")(),
             bit32.band(0xFF, 0x0F), bit32.bor(0xF0, 0x0F), bit32.bxor(0xFF, 0x0F),
             bit32.lshift(1, 31), bit32.rshift(0x80000000, 31), bit32.bnot(0),
             bit32.extract(0xF0, 4, 4), bit32.btest(2, 3), bit32.band(-1),
             math.mod(7, 3), math.log10(1000), math.ldexp(1, 3), math.frexp(8),
             table.maxn({1, 2, [10] = 3}), string.gfind == string.gmatch,
             math.atan2(1, 1) == math.atan(1, 1), load("return 40 + 2")())
end

h[0xB9] = function(id)
  wire.reply(id, gripper.state())
end

-- The finger functions, two-valued ones joined by ':'.
h[0xBA] = function(id)
  local function two(a, b)
    return wire.text(a) .. ":" .. wire.text(b)
  end
  -- Called by name (not through pcall, nor as a tail call), so that the
  -- error can name the function.
  local bad_ok, bad_err = pcall(function()
    local t = finger.type(2)
    return t
  end)
  wire.reply(id, finger.type(0), finger.type(1), finger.data(0),
             finger.data(1), finger.count(), finger.power(0),
             finger.power(1, false), finger.power(1), finger.power(1, true),
             two(finger.interface(0, "uart", 115200)),
             two(finger.bytes_available(1)), two(finger.write(0, {1})),
             two(finger.spi(1, {1, 2})), bad_ok,
             bad_err)
end

h[0xBB] = function(id)
  wire.reply(id, socket.gettime())
end

-- The readings of mc and grasping.
h[0xBC] = function(id)
  local f, limit = mc.force()
  local kp, ki, kd = mc.pid()
  wire.reply(id, mc.position(), mc.speed(), mc.blocked(), mc.busy(),
             mc.aforce(), f, limit, kp, ki, kd, grasping.state(),
             gripper.state())
end

-- mc and grasping calls: p[1] says which, floats from p[2] on.
local ops = {
  [1] = function(p) return mc.speed(wire.float(p, 2)) end,
  [2] = function() return mc.stop() end,
  [3] = function(p)
    return mc.move(wire.float(p, 2), wire.float(p, 6), p[10])
  end,
  [4] = function(p)
    -- p[2]: 0 no argument, 1 true (positive), 2 false (negative).
    if p[2] == 0 then return mc.homing() end
    return mc.homing(p[2] == 1)
  end,
  [5] = function(p) return mc.force(wire.float(p, 2)) end,
  [6] = function(p)
    return mc.pid(wire.float(p, 2), wire.float(p, 6), wire.float(p, 10))
  end,
  [7] = function(p) return grasping.move(wire.float(p, 2), wire.float(p, 6)) end,
  [8] = function(p)
    return grasping.grasp(wire.float(p, 2), wire.float(p, 6), wire.float(p, 10))
  end,
  [9] = function(p) return grasping.clamp(wire.float(p, 2), wire.float(p, 6)) end,
  [10] = function() return grasping.stop_clamping() end,
  [11] = function(p)
    return grasping.release(wire.float(p, 2), wire.float(p, 6))
  end,
  -- Integer arguments out of range: errors, not their low bits. Each
  -- called by name (not a tail call), so that the error names it.
  [12] = function()
    local function try(f)
      local ok, err = pcall(f)
      return ok and "ok" or err:gsub("^.-: ", "")
    end
    local big = 2^32 + 1
    return try(function() local r = mc.homing(big) return r end),
      try(function() local r = mc.homing(-1) return r end),
      try(function() local r = mc.move(50, 50, 256) return r end),
      try(function() local r = mc.move(50, 50, big) return r end),
      try(function() local r = cmd.register(big + 0xB0) return r end),
      try(function() local r = finger.type(2^32) return r end),
      try(function() local r = etob(2^32) return r end),
      mc.homing(3)
  end,
}
h[0xBD] = function(id, p)
  -- What the call returned, then the state it left at once.
  local r = table.pack(ops[p[1]](p))
  wire.reply(id, r.n, table.unpack(r, 1, r.n))
end

-- Modules: this one's helper came from beside it, socket from the host.
h[0xBE] = function(id)
  wire.reply(id, require("wire") == wire, package.loaded.wire.name,
             type(socket.gettime), require("socket") == socket)
end

-- The end: the loop returns and the script ends without an error.
h[0xBF] = function(id)
  wire.reply(id, "bye")
  return "stop"
end

wire.serve(h, function(id, p)
  -- IDs registered through B3h.
  wire.reply(id, "dyn", #p)
end)
