-- bench_echo.lua: the script of wsgbench's "script B0h round trip" rows.
-- It registers B0h and answers each B0h at once with E_SUCCESS and the
-- packet's own bytes, so the bench compares the round trip of a script's
-- ID with the firmware's 43h on the same daemon: the cost of the script
-- host is all that differs. Between packets it waits in cmd.read, which
-- is also what the "script in cmd.read" idle row measures.
cmd.register(0xB0)
while true do
  local id, payload = cmd.read()
  cmd.send(id, etob(E_SUCCESS), payload)
end
