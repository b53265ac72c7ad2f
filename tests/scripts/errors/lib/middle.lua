local deep = require("lib.deep")
local M = {}
function M.run() return deep.fail(3) end
return M
