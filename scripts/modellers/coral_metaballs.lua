-- The metaball object of the PGE thesis (Fig. 3.5, rendered in Figs. 3.6 and 3.13 left),
-- ported rule for rule: A -> B T A T B and B -> A T' B T' A (the Sierpinski arrowhead
-- curve), where A and B drop a charged particle and walk one step, and T turns. Marching
-- cubes wraps the particles in one smooth, coral-like surface. `wobble` lifts the particles
-- by noise so the flat curve becomes a reef.
local p = pge.params{
  iterations = {4, min = 0, max = 7, doc = "derivation steps"},
  angle = {60, min = 0, max = 180, doc = "turn of T, degrees"},
  distance = {0.5, min = 0.01, max = 10, doc = "step between particles"},
  charge = {1.0, min = 0.01, max = 10, doc = "charge of each particle"},
  radius = {0.6, min = 0.01, max = 10, doc = "radius of influence of each particle"},
  wobble = {0.6, min = 0, max = 10, doc = "height of the noise that lifts the particles"},
  resolution = {160, min = 8, max = 512, doc = "marching cubes cells along the longest side"},
}

local obj = pge.LSystem("metaball coral")
obj:axiom{ A{} }
obj:iterations(p.iterations)
obj:interpretEveryStep(false)

obj:createInstance(function()
  local inst = {}
  function inst:reset()
    self.pos, self.ang = {0, 0}, 0
    self.meta = pge.Metaballs{ radius = p.radius }
    self.mc = pge.MarchingCubes(self.meta, {
      resolution = p.resolution, iso = 0.5, material = { color = "#e8826a", roughness = 0.6 },
    })
  end
  function inst:model() return self.mc:model() end
  inst:reset()
  return inst
end)

obj:RRule("A", function() return { B{}, T{v = 1}, A{}, T{v = 1}, B{} } end)
obj:RRule("B", function() return { A{}, T{v = -1}, B{}, T{v = -1}, A{} } end)

-- A and B: a particle here, then a step forward.
local function drop()
  local x, z = this.pos[1], this.pos[2]
  local y = p.wobble * pge.noise.fbm(x * 0.25, z * 0.25, {octaves = 3})
  this.meta:addParticle({x, y, z}, p.charge)
  this.pos[1] = x + math.sin(this.ang) * p.distance
  this.pos[2] = z + math.cos(this.ang) * p.distance
  return true
end
obj:IRule("A", drop)
obj:IRule("B", drop)
obj:IRule("T", function(t)
  this.ang = this.ang + t.v * math.rad(p.angle)
  return true
end)
return obj
