-- debug is not available in the sandbox.
local info = debug.getinfo(1)
return info
