-- wire.lua: how the test scripts answer, for integ_script
-- (tests/integration/integ_script.c), and the module the scripts require
-- from beside them. A reply is E_SUCCESS, then values as text joined by
-- '|' (in pieces when it is long): numbers with 17 significant digits, so
-- that the test reads back the very double the script had (a whole number
-- prints as tostring writes it); booleans and nil as tostring writes them.
-- serve() is the scripts' main loop.
local wire = {name = "wire"}

function wire.text(v)
  if type(v) == "number" then
    -- NaN prints as "nan" or "-nan" depending on the C library.
    if v ~= v then return "nan" end
    return string.format("%.17g", v)
  end
  return tostring(v)
end

-- Every value, nils included (select keeps them, ipairs would stop).
function wire.join(...)
  local parts = {}
  for i = 1, select("#", ...) do
    parts[i] = wire.text((select(i, ...)))
  end
  return table.concat(parts, "|")
end

-- Text longer than one reply holds (the command set's 256 bytes of
-- parameters) goes in pieces: E_CMD_PENDING before each but the last, as
-- "more follows", and E_SUCCESS before the last.
local PIECE = 250

function wire.reply(id, ...)
  local text = wire.join(...)
  while #text > PIECE do
    cmd.send(id, etob(E_CMD_PENDING), text:sub(1, PIECE))
    text = text:sub(PIECE + 1)
  end
  return cmd.send(id, etob(E_SUCCESS), text)
end

-- The float32 at payload[i..i+3] (little-endian, as drivers pack it).
function wire.float(p, i)
  return bton({p[i], p[i + 1], p[i + 2], p[i + 3]})
end

-- The payload's bytes from i on as a string.
function wire.string(p, i)
  return string.char(table.unpack(p, i or 1))
end

-- Register an ID per handler and answer what comes, for good:
-- handlers[id](id, payload); IDs registered later without a handler go
-- to other. cmd.read runs inside pcall, as scripts on the gripper call
-- it: the wait must survive a protected call. A handler that returns
-- "stop" ends the loop, and with it the script.
function wire.serve(handlers, other)
  for id in pairs(handlers) do
    cmd.register(id)
  end
  while true do
    local ok, id, payload = pcall(cmd.read)
    if not ok then
      error(id, 0)
    end
    if (handlers[id] or other)(id, payload) == "stop" then
      return
    end
  end
end

return wire
