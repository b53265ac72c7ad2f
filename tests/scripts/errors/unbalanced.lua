-- A closing bracket without an opening one, met by the default interpretation.
local l = pge.LSystem("x")
l:axiom("F]]F")
return l
