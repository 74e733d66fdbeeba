-- fail.lua: a script that fails on request, for integ_script's checks of
-- D19/D20, "script status" and the traceback in "script output". B0h with
-- p[1] = 0 is answered; with 1 it raises an error two calls deep, which
-- ends the script.
local function explode(what)
  error("boom: " .. what)
end

local function middle(what)
  explode(what)
end

cmd.register(0xB0)
while true do
  local id, p = cmd.read()
  if p[1] == 1 then
    middle("asked to fail")
  end
  cmd.send(id, etob(E_SUCCESS))
end
