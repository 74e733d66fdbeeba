-- pd_control.lua: a position controller on the gripper, answering the
-- packets a UMI-style driver sends (docs: SCRIPTING.md, "How drivers use
-- scripts"). Written for the emulator's tests from that description; it
-- is the project's own, not a copy of any published script.
--
-- B0h (payload 00): the state, nothing else.
-- B1h (25 bytes: 00, then target position mm, target velocity mm/s, kp,
--      kd, travel force limit N, blocked force limit N, each a float32
--      LE): one step of a PD controller on the finger speed, then the
--      state.
-- Both are answered with 19 bytes: E_SUCCESS (2), the lowest byte of the
-- system state flags, then position, speed, motor force and the script's
-- clock (socket.gettime, simulated seconds) as float32 LE. Drivers of this
-- kind reject any other length, so a malformed request gets the 2-byte
-- E_CMD_FORMAT_ERROR and nothing else: the driver then fails loudly
-- instead of reading garbage.
--
-- The controller runs once per B1h, not on a clock of its own: the driver's
-- request rate (30 Hz for UMI) is the loop rate, and the speed set by one
-- step holds until the next. That keeps the script's behaviour in lockstep
-- with the packets, which is what a test stepping simulated time needs.

local socket = require("socket")

local ID_STATE = 0xB0
local ID_PD = 0xB1
local PD_LEN = 25

local function f32(p, at)
  return bton({p[at], p[at + 1], p[at + 2], p[at + 3]})
end

local function answer(id)
  cmd.send(id, etob(E_SUCCESS), gripper.state() % 256,
           ntob(mc.position()), ntob(mc.speed()), ntob(mc.aforce()),
           ntob(socket.gettime()))
end

-- One controller step toward (pos, vel): speed command = kp * position
-- error + kd * velocity error. The force limit follows the contact: the
-- travel limit while the fingers move freely, the blocked one once they
-- press on something, read right after the new speed is set (mc.blocked
-- is the physical state, so pushing on into the same contact keeps it).
local function pd_step(p)
  local pos, vel = f32(p, 2), f32(p, 6)
  local kp, kd = f32(p, 10), f32(p, 14)
  local travel_force, blocked_force = f32(p, 18), f32(p, 22)
  local v = kp * (pos - mc.position()) + kd * (vel - mc.speed())

  mc.speed(v)
  if mc.blocked() then
    mc.force(blocked_force)
  else
    mc.force(travel_force)
  end
end

cmd.register(ID_STATE)
cmd.register(ID_PD)
printf("pd_control: B0h B1h registered\n")

while true do
  local id, payload = cmd.read()

  if id == ID_PD and #payload == PD_LEN and payload[1] == 0 then
    pd_step(payload)
    answer(id)
  elseif id == ID_STATE then
    answer(id)
  else
    cmd.send(id, etob(E_CMD_FORMAT_ERROR))
  end
end
