-- The error is raised two modules down.
local m = require("lib.middle")
return m.run()
