-- Runs forever: the time limit stops it.
local i = 0
while true do
  i = i + 1
end
