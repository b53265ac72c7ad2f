return pge.load("sub/child.lua", { sise = 3 })
