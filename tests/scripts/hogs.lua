-- hogs.lua: work that runs inside the library's C functions, where the
-- count hook does not reach, for integ_script's part "hogs". B0h with
-- p[1] = N answers at once, then runs hog N for good, each call caught
-- with pcall so that an error does not end it; the first error a hog
-- sees is printed (the test reads it in "script output"). Meanwhile the
-- test sends Loop (06h) packets: every one must be answered within the
-- bound, and SIGTERM must end the daemon afterwards.
local big = 200000

local hogs = {}

-- %b() over 200 kB of '(' that never close: quadratic in the subject.
hogs[1] = function()
  local s = ("("):rep(big)
  return function() return s:find("%b()") end
end

-- A set of 100,000 characters: each subject byte scans all of it.
hogs[2] = function()
  local s = ("b"):rep(100000)
  local set = "[" .. ("a"):rep(100000) .. "]"
  return function() return s:find(set) end
end

-- A literal pattern of 100,000 bytes that fails at its end, at each of
-- 200,000 positions.
hogs[3] = function()
  local s = ("a"):rep(big)
  local p = ("a"):rep(100000) .. "b"
  return function() return s:match(p) end
end

-- A plain find of the same needle: memcmp at every position.
hogs[4] = function()
  local s = ("a"):rep(big)
  local p = ("a"):rep(100000) .. "b"
  return function() return s:find(p, 1, true) end
end

-- gsub whose '-' backtracks over the rest of the subject at each
-- position: quadratic, within the old pre-check's bound.
hogs[5] = function()
  local s = ("a"):rep(40000)
  return function() return s:gsub(".-b", "") end
end

-- cmd.send of five levels of 100 references to one table, each holding
-- 100 empty strings: 100^5 values to visit, none of them a byte.
hogs[6] = function()
  local t = ""
  for _ = 1, 5 do
    local up = {}
    for i = 1, 100 do up[i] = t end
    t = up
  end
  return function() return cmd.send(0xB1, t) end
end

-- A fresh coroutine each time, each looping for good, copying a string
-- of 1 kB at each turn (so that a slice of instructions is a long one).
hogs[7] = function()
  local s = ("x"):rep(1000)
  return function()
    local co = coroutine.create(function()
      while true do local _ = s .. "y" end
    end)
    return coroutine.resume(co)
  end
end

-- A message handler that loops (Lua calls it with the hooks off when the
-- hook raised the error).
hogs[8] = function()
  return function()
    return xpcall(error, function() while true do end end)
  end
end

-- A pattern where nothing can yield: %b() inside a __tostring.
hogs[9] = function()
  local s = ("("):rep(big)
  local t = setmetatable({}, {__tostring = function()
    return tostring(s:find("%b()"))
  end})
  return function() return tostring(t) end
end

-- A loop where nothing can yield: a load reader, which Lua calls from C.
-- Each ends in an error; the next starts at once.
hogs[10] = function()
  return function()
    local f, err = load(function() while true do end end)
    if not f then error(err, 0) end
  end
end

-- Library calls that work without instructions or allocation, in a loop:
-- full collections of 8 MB of tables,
hogs[11] = function()
  local keep = {}
  for i = 1, 100000 do keep[i] = {i} end
  return function() return collectgarbage() end
end

-- tonumber of a megabyte,
hogs[12] = function()
  local s = (" "):rep(1000000) .. "1"
  return function() return tonumber(s) end
end

-- insert and remove at the front of 200,000 elements,
hogs[13] = function()
  local t = {}
  for i = 1, 200000 do t[i] = i end
  return function()
    table.insert(t, 1, 0)
    return table.remove(t, 1)
  end
end

-- and string.rep of nothing 2^31 - 1 times (nothing to allocate, so
-- nothing the allocator counts).
hogs[14] = function()
  return function() return string.rep("", 2 ^ 31 - 1) end
end

cmd.register(0xB0)
local _, p = cmd.read()
local hog = hogs[p[1]]()
cmd.send(0xB0, etob(E_SUCCESS))
local said = false
while true do
  local ok, err = pcall(hog)
  if not ok and not said then
    print("hog error: " .. tostring(err))
    said = true
  end
end
