-- A unit box centred at the origin, one colour per material, cached per colour so every
-- box of a colour shares one mesh (the glb then instances it).
local box = {}
local cache = {}

local faces = {
  -- normal, then two axes spanning the face
  {{ 1, 0, 0}, {0, 1, 0}, {0, 0, -1}},
  {{-1, 0, 0}, {0, 1, 0}, {0, 0,  1}},
  {{ 0, 1, 0}, {1, 0, 0}, {0, 0,  1}},
  {{ 0,-1, 0}, {1, 0, 0}, {0, 0, -1}},
  {{ 0, 0, 1}, {0, 1, 0}, {1, 0,  0}},
  {{ 0, 0,-1}, {0, 1, 0}, {-1, 0, 0}},
}

function box.mesh(color)
  if cache[color] then return cache[color] end
  local positions, normals, uvs, indices = {}, {}, {}, {}
  for f, face in ipairs(faces) do
    local n, u, v = face[1], face[2], face[3]
    local base = (f - 1) * 4
    for _, c in ipairs{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}} do
      for k = 1, 3 do
        positions[#positions + 1] = 0.5 * (n[k] + c[1] * v[k] + c[2] * u[k])
        normals[#normals + 1] = n[k]
      end
      uvs[#uvs + 1] = (c[1] + 1) / 2
      uvs[#uvs + 1] = (c[2] + 1) / 2
    end
    for _, k in ipairs{0, 1, 2, 0, 2, 3} do indices[#indices + 1] = base + k end
  end
  local m = pge.mesh{positions = positions, normals = normals, uvs = uvs, indices = indices,
                     material = {color = color}, name = "box"}
  cache[color] = m
  return m
end

return box
