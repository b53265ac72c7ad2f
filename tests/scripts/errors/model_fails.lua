-- Returns an object whose :model() fails: that failure is what the user sees.
local thing = {}
function thing:model()
  error("the roof has no walls")
end
return thing
