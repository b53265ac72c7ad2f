-- A module outside the script folder and the library.
local m = require("../outside")
return m
