---@meta
-- LuaLS annotations for space colonization (pge.SpaceColonization), its envelopes
-- (pge.shape) and the tree options shared by every generator. Reference: docs/lua-api.md,
-- sections "Space colonization", "Shapes" and "Tree options".

---An envelope: where attraction points are drawn.
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
---`"sphere"`, `"ellipsoid"`, `"box"`, `"capsule"`, `"cone"`, `"cylinder"`, `"revolve"`,
---`"mesh"`, `"union"`, `"difference"` or `"predicate"`.
---@return string
function Shape:kind() end

pge.shape = {}

---A ball (`center` defaults to the origin; radius > 0). Positional: `{center, radius}`.
---@param o {center?: pge.Vector, radius: number}|table
---@return pge.Shape
function pge.shape.sphere(o) end

---Axis-aligned semi-axes `radii` (all > 0). Positional: `{center, radii}`.
---@param o {center?: pge.Vector, radii: pge.Vector}|table
---@return pge.Shape
function pge.shape.ellipsoid(o) end

---An axis-aligned box (min < max on every axis). Positional: `{min, max}`.
---@param o {min: pge.Vector, max: pge.Vector}|table
---@return pge.Shape
function pge.shape.box(o) end

---Points within `radius` (> 0) of the segment a-b. Positional: `{a, b, radius}`.
---@param o {a: pge.Vector, b: pge.Vector, radius: number}|table
---@return pge.Shape
function pge.shape.capsule(o) end

---A solid cone with a disc of `radius` (> 0) at `base` (base ~= apex).
---Positional: `{base, apex, radius}`.
---@param o {base: pge.Vector, apex: pge.Vector, radius: number}|table
---@return pge.Shape
function pge.shape.cone(o) end

---A solid cylinder between the disc centres a and b (a ~= b; radius > 0).
---Positional: `{a, b, radius}`.
---@param o {a: pge.Vector, b: pge.Vector, radius: number}|table
---@return pge.Shape
function pge.shape.cylinder(o) end

---A closed profile of at least 3 `{r, y}` points (r >= 0) revolved around the vertical axis
---through `center` (default the origin).
---@param o {profile: number[][]|{r: number, y: number}[], center?: pge.Vector}
---@return pge.Shape
function pge.shape.revolve(o) end

---The inside of a closed triangle mesh (ray parity): an .obj/.glb/.gltf file next to the
---script, or a mesh/model (anything with :model()); `transform` places it. Any mesh, closed
---or not, serves `mode = "vertices"`. Also `mesh("crown.obj")` and `mesh(model)`.
---@param o {path?: string, model?: pge.Modelish, transform?: pge.Mat4}|string|pge.Modelish
---@return pge.Shape
function pge.shape.mesh(o) end

---Inside any of the shapes (at least one).
---@param shapes pge.Shape[]
---@return pge.Shape
function pge.shape.union(shapes) end

---Inside `a` and not inside `b`.
---@param o {a: pge.Shape, b: pge.Shape}|pge.Shape[]
---@return pge.Shape
function pge.shape.difference(o) end

---Inside where `f` returns a value other than nil and false, within `bounds` (min < max).
---No surface, so not for `mode = "surround"`.
---@param f fun(p: pge.Vec3): any
---@param bounds {min: pge.Vector, max: pge.Vector}|pge.Vector[]|pge.Shape
---@return pge.Shape
function pge.shape.predicate(f, bounds) end

---How the skeleton becomes bark. Unknown keys are errors.
---@class pge.TreeMeshOptions
---@field sides? integer points per ring, 3..64 (8)
---@field caps? boolean close branch tips and root bases (true)
---@field exponent? number pipe-model exponent n in r^n = r1^n + r2^n, 1..4 (2.3)
---@field tipRadius? number radius at the tips, > 0 (0.02)
---@field mergeStraight? number|boolean merge straight chains turning less than this many degrees, 0..45 (off; true: 5)
---@field smoothing? number move each node this fraction toward its parent, 0..1 (0)
---@field radii? "pipe"|"keep" pipe model from tipRadius, or the generator's radii ("pipe"; turtle "keep")
---@field color? string bark colour "#rrggbb" of the procedural texture ("#6b5444")
---@field texture? string a PNG bark texture (relative to the script for SpaceColonization)
---@field bark? "furrowed"|"plated"|"smooth"|"fibrous"|{style?: string, depth?: number} procedural bark pattern ("furrowed"; depth 0..4, 1)
---@field textureSize? integer side of the procedural bark maps in pixels (16..2048, 512)
---@field textureScale? number metres of bark one texture tile covers (> 0, 0.6)
---@field light? number[] direction light comes from; branch UV seams face away ({0.45, 0.8, 0.35})
---@field flare? boolean|{roots?: integer, spread?: number, height?: number} trunk flare (off; roots 5, spread 1, height 1)

---Leaves hung at branch tips. Unknown keys are errors.
---@class pge.LeafOptions
---@field perTip? integer[]|integer leaves per tip {min, max}, 0..1000, min <= max ({3, 6}); n: {n, n}
---@field size? number leaf length, > 0 (0.25)
---@field width? number width as a fraction of the length, > 0 and <= 4 (1; 0.2 gives needles)
---@field colors? string[]|string two colours "#rrggbb" a leaf's colour is drawn between ({"#2f6b1f", "#7da83a"})
---@field maxDepth? integer leaves hang on a tip's last maxDepth + 1 segments, 0..1000 (2)
---@field texture? string a PNG leaf texture (alpha-masked) instead of the procedural silhouette
---@field shape? "ovate"|"lobed"|"lanceolate"|"palmate"|"needles" procedural leaf silhouette ("ovate")
---@field textureSize? integer side of the procedural leaf maps in pixels (16..2048, 512)

---The bark and leaf options every tree generator reads. Keys in `mesh` win over the
---shorthands `radius`, `smoothing` and `sides`.
---@class pge.TreeOptions
---@field radius? {tip?: number, exponent?: number}|number shorthand for mesh.tipRadius / mesh.exponent (a number: the tip radius)
---@field smoothing? number shorthand for mesh.smoothing, 0..1
---@field sides? integer shorthand for mesh.sides, 3..64
---@field mesh? pge.TreeMeshOptions
---@field leaves? pge.LeafOptions|boolean true: default leaves; false or absent: none

---Options of pge.SpaceColonization; any other key is an error.
---@class pge.SpaceColonizationOptions: pge.TreeOptions
---@field envelope pge.Shape where the attraction points are (required)
---@field points? integer number of points, 1..10000000 (2000; "vertices": every vertex)
---@field mode? "fill"|"surround"|"vertices" inside, a shell under the surface, or a mesh envelope's vertices ("fill")
---@field thickness? number shell thickness for "surround", > 0 (15% of the envelope's smallest extent)
---@field step? number segment length, > 0 (1/50 of the envelope's bounding-box diagonal)
---@field influence? number attraction radius, > 0 (8 steps; at least 4 kills if only kill is given)
---@field kill? number removal distance, > 0 and < influence (2 steps; at most influence/4 if only influence is given)
---@field tropism? pge.Vector added to each unit growth direction ({0, 0, 0})
---@field root? pge.Vector the root ({0, 0, 0})
---@field roots? pge.Vector[] several roots (a bush); wins over root
---@field trunk? number length of a straight vertical trunk grown first, >= 0 (0)
---@field maxIterations? integer iteration cap, 1..1000000 (1000); reaching it adds a warning
---@field seed? integer mixed into the run's seed, >= 0 (0: the run's seed alone)
---@field start? pge.Skeleton grow on from this skeleton's tips; its nodes come first, unchanged

---Space colonization (Runions et al. 2007): one step of the returned algorithm is one
---growth iteration.
---@param o pge.SpaceColonizationOptions
---@return pge.AlgorithmHandle
function pge.SpaceColonization(o) end

---Options of pge.Growth (nutrient transport, seed 001); any other key is an error.
---@class pge.GrowthOptions: pge.TreeOptions
---@field ratio? number share of the passed feed for child A, in (0, 1) (0.6)
---@field spread? number weight of the perpendicular direction at a split, >= 0 (0.45)
---@field splitsize? number length at which a trunk branch splits, > 0 (2.5)
---@field splitdecay? number the split length shrinks by exp(-splitdecay * depth), >= 0 (0.01)
---@field directedness? number turn from dense foliage (1) or at random (0), 0..1 (0.5)
---@field localdepth? integer ancestors climbed by the leaf-density query, 0..1000 (2)
---@field feed? number nutrient fed at each step, > 0 (1)
---@field steps? integer feedings, 0..100000 (60); --steps overrides
---@field root? pge.Vector where the trunk starts ({0, 0, 0})
---@field direction? pge.Vector the trunk's first direction ({0, 1, 0})
---@field start? pge.Skeleton grow on from this skeleton's tips; its nodes come first, unchanged
---@field scale? number lengths and radii multiplier, > 0 (1)
---@field girth? number further radius multiplier, > 0 (0.4)
---@field maxBranches? integer the branch cap, 1..50000000 (1000000)
---@field seed? integer mixed into the run's seed, >= 0 (0)

---Growth by nutrient transport: one step of the returned algorithm is one feeding.
---@param o pge.GrowthOptions
---@return pge.AlgorithmHandle
function pge.Growth(o) end

---Options of pge.Conifer (an excurrent tree: leader, whorls, flat sprays); any other key is an error.
---@class pge.ConiferOptions: pge.TreeOptions
---@field years? integer years grown, one internode and one whorl a year, 1..1000 (20); --steps overrides
---@field height? number height after `years` years, > 0 (12)
---@field crownRadius? number length of the longest first-order branch after `years` years, > 0 (3)
---@field crown? "conic"|"ogive"|"columnar"|number[] how branch lengths fall toward the apex; a list: relative lengths from the apex to the crown base ("conic")
---@field crownBase? number fraction of the height below which branches are shed, 0..0.95 (0.1)
---@field perWhorl? integer[]|integer first-order branches per whorl {min, max}, 1..12 ({4, 6})
---@field interwhorl? integer[]|integer small branches between two whorls {min, max}, 0..8 ({0, 0})
---@field twist? number degrees each whorl is turned from the one below, -360..360 (137.5)
---@field angle? number[] {apex, base} degrees between a branch and the trunk above it, 0..180 ({60, 95})
---@field droop? number degrees the tip of the longest branch bends down, 0..90 (20)
---@field jitter? number random variation of azimuths, angles and lengths, 0..1 (0.15)
---@field waviness? number sideways wander of whorl nodes, fraction of the internode, 0..0.5 (0.02)
---@field segment? number segment length of branches and shoots (shoots grow at nodes), > 0 (0.25)
---@field orders? integer 1: branches; 2: with shoots; 3: shoots of shoots (2)
---@field sprayAngle? number degrees between a shoot and its parent, 0..90 (55)
---@field sprayLength? number shoot length, fraction of the parent's length beyond it, 0..2 (0.5)
---@field sprayDroop? number degrees the tip of a shoot bends down, 0..90 (10)
---@field sprayPattern? "alternate"|"paired" one shoot per node or two ("alternate")
---@field bare? number fraction of each branch, from the trunk, without shoots, 0..1 (0.1)
---@field jointRatio? number largest branch radius / trunk radius at a joint, (0, 1] (0.45)
---@field root? pge.Vector the base of the trunk ({0, 0, 0})
---@field seed? integer mixed into the run's seed, >= 0 (0)
---@field maxNodes? integer the node cap, 1..50000000 (2000000)

---An excurrent tree (pine, spruce): one step of the returned algorithm is one year.
---@param o pge.ConiferOptions
---@return pge.AlgorithmHandle
function pge.Conifer(o) end

---The branch graph every tree generator produces. Nodes are 1-based; a root's parent is 0.
---@class pge.Skeleton
local Skeleton = {}
---@return integer
function Skeleton:count() end
---@param i integer
---@return pge.Vec3
function Skeleton:position(i) end
---@param i integer
---@return integer parent 0 for a root
function Skeleton:parent(i) end
---@param i integer
---@return number
function Skeleton:radius(i) end
---@param i integer
---@return integer order 0 along the trunk, +1 per lateral branch
function Skeleton:order(i) end
---@param i integer
---@return integer forks between the root and the node
function Skeleton:depth(i) end
---@return integer[]
function Skeleton:tips() end
---@param i integer
---@return integer[]
function Skeleton:children(i) end
---Adds a node (parent 0: a new root) and returns its index.
---@param parent integer
---@param position pge.Vector
---@param radius? number
---@return integer
function Skeleton:add(parent, position, radius) end
---@return pge.Skeleton
function Skeleton:copy() end
---@return integer
function Skeleton:leafCount() end

---An empty skeleton (also `pge.Skeleton.new()`).
---@type table|fun(): pge.Skeleton
pge.Skeleton = {}

---Options of pge.tree.
---@class pge.TreeCallOptions: pge.TreeOptions
---@field skeleton pge.Skeleton the skeleton to mesh (required)
---@field seed? integer mixed into the run's seed for the leaves, >= 0 (0)

---Meshes any skeleton with the common bark and leaf options.
---@param o pge.TreeCallOptions
---@return pge.Model
function pge.tree(o) end
