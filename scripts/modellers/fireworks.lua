-- Fireworks (ML-System paper §5.2, Figs. 4-5; PGE thesis Fig. 3.14): a context-sensitive
-- L-system drawn with the line generator, where every derivation step is one frame of the
-- animation: `pge run fireworks.lua --steps k` writes frame k.
--
-- Symbols (after the paper): a rocket's head A rises, leaving tail segments L behind it; B
-- marks where a tail begins. When its fuse burns out the head becomes E, which bursts into
-- arms F flying in random directions under gravity, each leaving its own L segments. An L
-- fades every frame; once dim it becomes a B, and of two neighbouring Bs the first is
-- deleted by the context-sensitive rule `B > B`, so spent trails leave the string.
local p = pge.params{
  rockets = {4, min = 1, max = 50, doc = "rockets"},
  arms = {24, min = 3, max = 200, doc = "arms per burst"},
  frames = {42, min = 1, max = 1000,
            doc = "derivation steps: the frame written (the default shows three bursts lit)"},
  fade = {0.82, min = 0.1, max = 0.99, doc = "brightness kept by a trail segment per frame"},
  width = {0.15, min = 0, max = 2,
           doc = "trail thickness in metres (thin tubes); 0 writes glTF lines, which some "
              .. "clients (Blender) import as edges that do not render"},
}

local dt, gravity = 1 / 12, pge.vec3(0, -9.8, 0)
local palette = {
  {1.0, 0.35, 0.2}, {0.3, 0.8, 1.0}, {1.0, 0.85, 0.3}, {0.6, 1.0, 0.4}, {1.0, 0.4, 0.9},
}

local obj = pge.LSystem("fireworks")
obj:iterations(p.frames)

-- Every rocket waits its turn (delay in frames), then rises for `fuse` seconds.
local rng = pge.rng(pge.seed())
local axiom = {}
for i = 1, p.rockets do
  local x, z = rng:range(-12, 12), rng:range(-6, 6)
  axiom[#axiom + 1] = B{}
  axiom[#axiom + 1] = A{
    pos = pge.vec3(x, 0, z),
    vel = pge.vec3(rng:range(-2, 2), rng:range(22, 28), rng:range(-1, 1)),
    fuse = rng:range(1.0, 1.4),
    delay = (i - 1) * 6 + rng:int(0, 3),
    color = palette[(i - 1) % #palette + 1],
  }
end
obj:axiom(axiom)

obj:createInstance(function()
  local show = {}
  function show:reset() self.lines = pge.Lines{ width = p.width } end
  function show:model() return self.lines:model() end
  show:reset()
  return show
end)

-- The head rises, leaving a segment; when the fuse is out it explodes.
obj:RRule("A", function(a)
  if a.delay > 0 then
    return A{pos = a.pos, vel = a.vel, fuse = a.fuse, delay = a.delay - 1, color = a.color}
  end
  if a.fuse <= 0 then
    return E{pos = a.pos, color = a.color}
  end
  local vel = a.vel + gravity * dt
  local pos = a.pos + vel * dt
  return {
    L{from = a.pos, to = pos, bright = 1, color = {1, 0.9, 0.7}},
    A{pos = pos, vel = vel, fuse = a.fuse - dt, delay = 0, color = a.color},
  }
end)

-- The burst: arms in random directions (uniform on the sphere), each starting a new trail.
obj:RRule("E", function(e)
  local out = {}
  for _ = 1, p.arms do
    local z = 2 * pge.random() - 1
    local t = 2 * math.pi * pge.random()
    local s = math.sqrt(1 - z * z)
    local speed = 7 + 3 * pge.random()
    out[#out + 1] = B{}
    out[#out + 1] = F{
      pos = e.pos, vel = pge.vec3(s * math.cos(t), z, s * math.sin(t)) * speed,
      life = 1.2 + 0.6 * pge.random(), color = e.color,
    }
  end
  return out
end)

-- An arm falls under gravity, with drag, until its life is spent.
obj:RRule("F", function(f)
  if f.life <= 0 then return B{} end
  local vel = (f.vel + gravity * dt * 0.5) * 0.97
  local pos = f.pos + vel * dt
  return {
    L{from = f.pos, to = pos, bright = 1, color = f.color},
    F{pos = pos, vel = vel, life = f.life - dt, color = f.color},
  }
end)

-- A trail segment fades; once dim it becomes a B.
obj:RRule("L", function(l)
  local bright = l.bright * p.fade
  if bright < 0.05 then return B{} end
  return L{from = l.from, to = l.to, bright = bright, color = l.color}
end)

-- Two Bs together: the first one goes (context-sensitive cleaning).
obj:RRule("B > B", function() return {} end)

local function colour(c, k)
  return {math.min(1, c[1] * k), math.min(1, c[2] * k), math.min(1, c[3] * k)}
end

obj:IRule("L", function(l)
  this.lines:add(l.from, l.to, colour(l.color, l.bright))
  return true
end)
-- Heads are drawn as a short bright streak along their motion.
obj:IRule("A", function(a)
  if a.delay == 0 then this.lines:add(a.pos, a.pos - a.vel * (dt * 0.5), {1, 1, 0.9}) end
  return true
end)
obj:IRule("F", function(f)
  this.lines:add(f.pos, f.pos - f.vel * (dt * 0.5), colour(f.color, 1.3))
  return true
end)
return obj
