-- clock.lua: a script that lives by sleep, for integ_script's lockstep
-- checks. B0h starts it with a period (ms, u16 little-endian) and answers
-- the clock at the start; from then on it sleeps one period at a time and
-- counts, and answers each B1h that came during a sleep with the count and
-- socket.gettime() when it wakes. With time paused and stepped by the
-- test, every number is exact and the same on every run.
local wire = require "wire"
local socket = require "socket"

cmd.register(0xB0)
cmd.register(0xB1)

local id, p = cmd.read()
while id ~= 0xB0 do
  wire.reply(id, "not started")
  id, p = cmd.read()
end
local period = p[1] + 256 * p[2]
wire.reply(id, socket.gettime())

local n = 0
while true do
  sleep(period)
  n = n + 1
  while cmd.available() > 0 do
    wire.reply((cmd.read()), n, socket.gettime())
  end
end
