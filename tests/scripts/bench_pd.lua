-- bench_pd.lua: the script of wsgbench's "script PD" rows, the loop of
-- UMI's script: each B1h is one step of a PD controller on mc.speed, and
-- its answer the gripper's state, so the bench can drive it at rising
-- rates and count the answers.
--
-- B1h, 25 bytes: 00, then as float32 (little-endian) the target position
-- (mm), the target velocity (mm/s), kp, kd, the force limit while moving
-- and the force limit while blocked (N). The answer, 19 bytes as UMI's
-- driver expects them: E_SUCCESS, the lowest byte of the state flags,
-- then position, speed, motor force and the script's clock (s) as
-- float32. B0h (UMI's first packet) is answered E_SUCCESS; anything else
-- registered, or a B1h of another length, E_CMD_FORMAT_ERROR.
local socket = require "socket"

-- The drive's own limit (the WSG 50's 420 mm/s, with margin): a large
-- error asks for more than mc.speed accepts.
local VMAX = 400

local function f32(p, i)
  return bton({p[i], p[i + 1], p[i + 2], p[i + 3]})
end

cmd.register(0xB0)
cmd.register(0xB1)
while true do
  local id, p = cmd.read()
  if id == 0xB1 and #p == 25 then
    local pos, vel = f32(p, 2), f32(p, 6)
    local kp, kd = f32(p, 10), f32(p, 14)
    local travel_force, blocked_force = f32(p, 18), f32(p, 22)
    local v = kp * (pos - mc.position()) + kd * (vel - mc.speed())
    v = math.max(-VMAX, math.min(VMAX, v))
    mc.force(mc.blocked() and blocked_force or travel_force)
    mc.speed(v)
    cmd.send(id, etob(E_SUCCESS), bit32.band(gripper.state(), 0xFF),
             ntob(mc.position()), ntob(mc.speed()), ntob(mc.aforce()),
             ntob(socket.gettime()))
  elseif id == 0xB0 then
    cmd.send(id, etob(E_SUCCESS))
  else
    cmd.send(id, etob(E_CMD_FORMAT_ERROR))
  end
end
