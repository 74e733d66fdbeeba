-- dialect.lua: the gripper's Lua, difference by difference, for
-- integ_script's dialect part. Scripts of the gripper's era rely on each
-- of these; docs/scripting.md has the table they come from. Each answer
-- is one line of "name=value" pairs joined by ';', so that a failure in
-- the test names what differs.
local wire = require "wire"
require "oldmod"

local function compiles(src)
  local f = loadstring(src)
  return f ~= nil
end

local h = {}

-- Numbers: doubles only, printed as Lua 5.1 and 5.2 print them.
h[0xB0] = function(id)
  local t = {}
  t[1.0] = "one"
  wire.reply(id, table.concat({
    "int=" .. tostring(3), "float=" .. tostring(3.0), "half=" .. 7 / 2,
    "ten=" .. 10 / 2, "big=" .. tostring(2 ^ 53), "concat=" .. 1e15,
    "d=" .. string.format("%d", 2.5), "x=" .. string.format("%x", 255.9),
    "key=" .. tostring(t[1]), "mod=" .. 7.5 % 2
  }, ";"))
end

-- Syntax: no integer division, no bitwise operators, no attributes; goto
-- is Lua 5.2's.
h[0xB1] = function(id)
  wire.reply(id, table.concat({
    "idiv=" .. tostring(compiles("return 7 // 2")),
    "band=" .. tostring(compiles("return 1 & 3")),
    "shl=" .. tostring(compiles("return 1 << 3")),
    "bnot=" .. tostring(compiles("return ~1")),
    "const=" .. tostring(compiles("local x <const> = 1")),
    "goto=" .. tostring(compiles("goto a; ::a::"))
  }, ";"))
end

-- Names: those of Lua 5.1 and 5.2 are there, those of 5.3 and 5.4 not.
h[0xB2] = function(id)
  local a, b, c = unpack({1, 2, 3})
  wire.reply(id, table.concat({
    "unpack=" .. (a + b + c), "pow=" .. math.pow(2, 10),
    "loadstring=" .. loadstring("return 1 + 1")(),
    "module=" .. oldmod.twice(21), "getn=" .. table.getn({1, 2, 3}),
    "maxn=" .. table.maxn({1, 2, [10] = 3}), "mathmod=" .. math.mod(7, 3),
    "log10=" .. math.log10(1000), "ldexp=" .. math.ldexp(1, 3),
    "bit32=" .. bit32.band(0xFF, 0x0F),
    "gfind=" .. tostring(string.gfind == string.gmatch),
    "mathtype=" .. type(math.type), "utf8=" .. type(utf8),
    "move=" .. type(table.move), "maxint=" .. type(math.maxinteger),
    "nan=" .. type(math.nan), "pack=" .. type(string.pack),
    "close=" .. type(coroutine.close), "setfenv=" .. type(setfenv)
  }, ";"))
end

-- Patterns: an empty match right after a match counts, as in Lua 5.2.
h[0xB3] = function(id)
  local words = {}
  for w in string.gmatch("abc", "%w*") do words[#words + 1] = "[" .. w .. "]" end
  local s, n = string.gsub("hello world", "%w*", "x")
  local _, all = string.gsub("aaa", "a", "b", -1)
  wire.reply(id, table.concat({
    "gmatch=" .. table.concat(words), "gsub=" .. s .. "/" .. n,
    "negative=" .. all
  }, ";"))
end

wire.serve(h)
