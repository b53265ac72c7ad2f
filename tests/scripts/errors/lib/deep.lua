local D = {}
function D.fail(n)
  local t = nil
  return t.field + n -- line 4: indexing nil
end
return D
