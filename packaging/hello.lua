-- Answers B0h with E_SUCCESS, the finger opening and the simulated time.
local socket = require "socket"
cmd.register(0xB0)
print("hello.lua: B0h registered")
while true do
  local id, payload = cmd.read()
  cmd.send(id, etob(E_SUCCESS), ntob(mc.position()), ntob(socket.gettime()))
end
