-- sandbox.lua: what a script must not be able to do, for integ_script.
-- Each try runs inside the script and answers what happened, for the test
-- to compare with what the sandbox promises (src/script/script.h): no
-- io, os.execute, loadlib or debug, text chunks only, modules only from
-- beside the script, a memory cap, and preemption of loops, in the body,
-- in its coroutines and in the pattern functions. The test runs
-- a copy of it in a directory of its own, with a module outside that
-- directory and a precompiled chunk beside it.
local wire = require "wire"

-- What a call gave: "ok:" and its values, "nil:" and the reason for a
-- load that refused, "error:" and the message of one that raised; only
-- the first line of a message, unless whole.
local function outcome(ok, a, b, whole)
  local msg = tostring(a)
  if whole then
    msg = msg:gsub("\n%s*", " ")
  else
    msg = msg:match("[^\n]*")
  end
  if ok == nil then return "nil:" .. msg end
  if not ok then return "error:" .. msg end
  return "ok:" .. msg .. (b ~= nil and ":" .. tostring(b) or "")
end

local function dumped()
  return string.dump(function() return 42 end)
end

local h = {}

-- The libraries that are not there, and loading what is not text.
h[0xB0] = function(id)
  local chunk = dumped()
  local pieces = {chunk:sub(1, 4), chunk:sub(5)}
  local function reader()
    return table.remove(pieces, 1)
  end
  wire.reply(id,
    type(os.execute), outcome(pcall(os.execute, "true")), type(os.exit),
    type(os.getenv), type(os.remove), type(io), outcome(pcall(require, "io")),
    type(debug), outcome(pcall(require, "debug")), type(package.loadlib),
    type(loadfile), type(dofile), type(require("os").execute),
    outcome(load(chunk)), outcome(load(chunk, "dump", "b")),
    outcome(loadstring(chunk)), outcome(load(reader)),
    outcome(pcall(require, "../outside")), package.cpath)
end

-- A precompiled chunk beside the script (binmod.lua, from B2h's bytes),
-- then a module outside the directory, by package.path set to p (a
-- directory).
h[0xB1] = function(id, p)
  local bin_ok, bin_err = pcall(require, "binmod")
  -- linked.lua beside the script is a symbolic link to a file outside.
  local link_ok, link_err = pcall(require, "linked")
  -- linkdir beside the script is a symbolic link to a directory outside
  -- holding mod.lua; sub is a directory holding real.lua.
  local dir_ok, dir_err = pcall(require, "linkdir.mod")
  local sub_ok, sub = pcall(require, "sub.real")
  package.path = wire.string(p) .. "/?.lua"
  local ok, err = pcall(require, "outside")
  wire.reply(id, outcome(ok, err), outcome(bin_ok, bin_err, nil, true),
             outcome(link_ok, link_err, nil, true),
             outcome(dir_ok, dir_err, nil, true), outcome(sub_ok, sub))
end

-- A precompiled chunk, for the test to put beside the script.
h[0xB2] = function(id)
  cmd.send(id, etob(E_SUCCESS), dumped())
end

-- A loop that never waits: the host must preempt it.
h[0xB3] = function()
  while true do end
end

-- A table that grows past the memory cap.
h[0xB4] = function()
  local t = {}
  while true do
    t[#t + 1] = string.rep("x", 1000) .. #t
  end
end

-- Loops where the script cannot be preempted, in functions Lua calls from
-- C: a sort's comparison, a __tostring, a load reader. Each must end in an
-- error. A coroutine of the script's own is preempted like the body: one
-- that counts for some 30 slices ends, and says so.
h[0xB5] = function(id)
  local handled = {pcall(table.sort, {3, 2, 1}, function()
    while true do end
  end)}
  local shown = {pcall(tostring, setmetatable({}, {__tostring = function()
    while true do end
  end}))}
  local loaded = {load(function() while true do end end)}
  local co = coroutine.wrap(function()
    local n = 0
    for i = 1, 3000000 do n = n + i end
    return n
  end)
  wire.reply(id, outcome(handled[1], handled[2]), outcome(shown[1], shown[2]),
             outcome(loaded[1], loaded[2]), co())
end

-- A finalizer: Lua would run it with no hook, where a loop could not be
-- preempted; the host's setmetatable marks no table for one.
h[0xB6] = function(id)
  local ran = false
  local mt = {__gc = function()
    ran = true
    while true do end
  end}
  local t = setmetatable({}, mt)
  local same = getmetatable(t) == mt
  t = nil
  collectgarbage()
  collectgarbage()
  wire.reply(id, ran, same, rawget(mt, "__gc") ~= nil)
end

-- A loop around a stuck __tostring, each error caught: the script keeps
-- running stuck code, and the host must still get the processor back.
h[0xB8] = function()
  local t = setmetatable({}, {__tostring = function() while true do end end})
  while true do
    pcall(tostring, t)
  end
end

-- The pattern functions yield across themselves: a pattern that
-- backtracks for millions of steps runs (preempted) and answers, and one
-- the old pre-check refused for its worst case works; a malformed one
-- fails as in Lua. A plain find and an anchored match of any size work.
h[0xB9] = function(id)
  local lazy = string.find(("a"):rep(100000), (".-"):rep(10) .. "a")
  local _, quadratic = string.gsub(("1"):rep(2000), "%d+x", "")
  local _, key = pcall(string.match, "key = value", "^(%w+)%s*=%s*(%w+)$")
  local plain = string.find(("a"):rep(100000) .. "b", "b", 1, true)
  local anchored = #(string.match(("x"):rep(100000), "^(x*)$"))
  local _, bad = pcall(string.find, "a", "[a")
  wire.reply(id, lazy, quadratic, key, plain, anchored, bad)
end

h[0xB7] = function(id, p)
  cmd.send(id, etob(E_SUCCESS), p)
end

wire.serve(h)
