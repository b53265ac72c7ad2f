---@meta
-- LuaLS annotations for pge.SpaceColonization and pge.shape (plugin pge-spacecol).
-- Add this folder next to docs/lua in "workspace.library" of .luarc.json.

---@class pge.Shape
local Shape = {}
---Whether a point is inside.
---@param p pge.Vector
---@return boolean
function Shape:contains(p) end
---The two corners of the bounding box.
---@return pge.Vec3 min
---@return pge.Vec3 max
function Shape:bounds() end
---`"sphere"`, `"mesh"`, `"union"`, ...
---@return string
function Shape:kind() end

pge.shape = {}

---@param o {center?: pge.Vector, radius: number}
---@return pge.Shape
function pge.shape.sphere(o) end

---@param o {center?: pge.Vector, radii: pge.Vector}
---@return pge.Shape
function pge.shape.ellipsoid(o) end

---@param o {min: pge.Vector, max: pge.Vector}
---@return pge.Shape
function pge.shape.box(o) end

---Points within `radius` of the segment a-b.
---@param o {a: pge.Vector, b: pge.Vector, radius: number}
---@return pge.Shape
function pge.shape.capsule(o) end

---A solid cone with a disc of `radius` at `base`.
---@param o {base: pge.Vector, apex: pge.Vector, radius: number}
---@return pge.Shape
function pge.shape.cone(o) end

---@param o {a: pge.Vector, b: pge.Vector, radius: number}
---@return pge.Shape
function pge.shape.cylinder(o) end

---A closed profile of {r, y} points revolved around the vertical axis through `center`.
---@param o {profile: number[][], center?: pge.Vector}
---@return pge.Shape
function pge.shape.revolve(o) end

---The inside of a closed mesh: an .obj/.glb/.gltf file next to the script, or a model.
---@param o {path?: string, model?: pge.Modelish, transform?: pge.Mat4}|string
---@return pge.Shape
function pge.shape.mesh(o) end

---Inside any of the shapes.
---@param shapes pge.Shape[]
---@return pge.Shape
function pge.shape.union(shapes) end

---Inside `a` and not inside `b`.
---@param o {a: pge.Shape, b: pge.Shape}|pge.Shape[]
---@return pge.Shape
function pge.shape.difference(o) end

---Inside where `f` returns true, within `bounds`.
---@param f fun(p: pge.Vec3): boolean
---@param bounds {min: pge.Vector, max: pge.Vector}|pge.Shape
---@return pge.Shape
function pge.shape.predicate(f, bounds) end

---@class pge.TreeMeshOptions
---@field sides? integer ring resolution, 3..64 (8)
---@field caps? boolean close branch tips (true)
---@field exponent? number pipe-model exponent, 1..4 (2.3)
---@field tipRadius? number radius at the tips (0.02)
---@field mergeStraight? number|boolean merge straight chains turning less than this many degrees (true: 5)
---@field smoothing? number move each node this fraction toward its parent, 0..1 (0)
---@field radii? "pipe"|"keep" pipe model, or the generator's radii
---@field color? string bark colour "#rrggbb" of the procedural texture
---@field texture? string a PNG bark texture next to the script

---@class pge.LeafOptions
---@field perTip? integer[]|integer leaves per tip {min, max} ({3, 6})
---@field size? number leaf length (0.25)
---@field width? number width as a fraction of the length, 0..4 (1; 0.3 for needles)
---@field colors? string[]|string two colours a leaf's colour is drawn between
---@field maxDepth? integer leaves hang on a tip's last maxDepth + 1 segments (2)
---@field texture? string a PNG leaf texture (alpha-masked) next to the script

---@class pge.SpaceColonizationOptions
---@field envelope pge.Shape where the attraction points are
---@field points? integer number of points (2000)
---@field mode? "fill"|"surround"|"vertices"
---@field thickness? number shell thickness for "surround"
---@field step? number segment length
---@field influence? number attraction radius
---@field kill? number removal distance (< influence)
---@field tropism? pge.Vector added to each unit growth direction
---@field root? pge.Vector
---@field roots? pge.Vector[] several roots (a bush)
---@field trunk? number length of a straight vertical trunk grown first
---@field maxIterations? integer iteration cap (1000)
---@field seed? integer mixed into the run's seed (0)
---@field radius? {tip?: number, exponent?: number}
---@field smoothing? number
---@field sides? integer
---@field mesh? pge.TreeMeshOptions
---@field leaves? pge.LeafOptions|false

---Space colonization: one step of the returned algorithm is one growth iteration.
---@param o pge.SpaceColonizationOptions
---@return pge.AlgorithmHandle
function pge.SpaceColonization(o) end
