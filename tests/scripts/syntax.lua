-- syntax.lua: a script that does not compile (line 4 below), for
-- integ_script: "script run" and --script refuse it and D20 is set.
cmd.register(0xB0)
while true do cmd.read( end
