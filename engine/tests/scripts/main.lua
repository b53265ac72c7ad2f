local p = pge.params{ n = 2 }
local child = pge.load("sub/child.lua", { size = p.n * 3 })
local again = require("sub.counter")
local again2 = require("sub.counter")
assert(again == again2, "require caches modules")
return { child = child, count = again.count }
