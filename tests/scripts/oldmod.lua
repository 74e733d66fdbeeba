-- oldmod.lua: a module written as modules of Lua 5.1 were, with module()
-- and package.seeall, for dialect.lua.
module("oldmod", package.seeall)

function twice(x)
  return 2 * x
end
