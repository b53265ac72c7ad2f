-- A turtle whose bark texture is a file next to this script.
local l = pge.LSystem("textured")
l:axiom("F(2) [ +(30) F ] F")
l:createInstance(function() return pge.turtle{ mesh = {texture = "bark.png"} } end)
return l
