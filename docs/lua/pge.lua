---@meta
-- LuaLS (lua-language-server) annotations for PGE scripts.
-- Add this folder to "workspace.library" in .luarc.json for completion and type checks.

---@class pge
pge = {}

---@alias pge.Vector pge.Vec3|number[]|{x: number, y: number, z: number}
---@alias pge.Modelish pge.Mesh|pge.Model|{model: fun(self): pge.Model}

---Declares parameters and returns their values after `--set` / preview overrides.
---@param spec table<string, number|boolean|string|{[1]: number|boolean|string, min?: number, max?: number, doc?: string}>
---@return table<string, any>
function pge.params(spec) end

---The run's seed (`--seed`).
---@return integer
function pge.seed() end

---Uniform in [0, 1) from the current generator (the instance's inside an L-system rule).
---@return number
function pge.random() end

---@class pge.Rng
local Rng = {}
---@return number
function Rng:uniform() end
---@param a number
---@param b number
---@return number
function Rng:range(a, b) end
---@param a integer
---@param b integer
---@return integer
function Rng:int(a, b) end
---@param mu? number
---@param sigma? number
---@return number
function Rng:normal(mu, sigma) end
---@generic T
---@param array T[]
---@return T
function Rng:choice(array) end

---An independent Mersenne Twister (MT19937).
---@param seed? integer
---@return pge.Rng
function pge.rng(seed) end

---@class pge.Vec3
---@field x number
---@field y number
---@field z number
---@operator add(pge.Vector): pge.Vec3
---@operator sub(pge.Vector): pge.Vec3
---@operator mul(number|pge.Vector): pge.Vec3
---@operator div(number): pge.Vec3
---@operator unm: pge.Vec3
local Vec3 = {}
---@param other pge.Vector
---@return number
function Vec3:dot(other) end
---@param other pge.Vector
---@return pge.Vec3
function Vec3:cross(other) end
---@return number
function Vec3:length() end
---@param other pge.Vector
---@return number
function Vec3:distance(other) end
---@return pge.Vec3
function Vec3:normalize() end
---@param other pge.Vector
---@param t number
---@return pge.Vec3
function Vec3:lerp(other, t) end
---@return number, number, number
function Vec3:unpack() end

---@param x number|pge.Vector
---@param y? number
---@param z? number
---@return pge.Vec3
function pge.vec3(x, y, z) end

---@class pge.Quat
---@operator mul(pge.Quat): pge.Quat
---@operator mul(pge.Vector): pge.Vec3
local Quat = {}
---@return pge.Quat
function Quat:inverse() end
---@return pge.Quat
function Quat:normalize() end

pge.quat = {}
---@param axis pge.Vector
---@param degrees number
---@return pge.Quat
function pge.quat.axisAngle(axis, degrees) end
---@return pge.Quat
function pge.quat.identity() end
---@param from pge.Vector
---@param to pge.Vector
---@return pge.Quat
function pge.quat.between(from, to) end

---@class pge.Mat4
---@operator mul(pge.Mat4): pge.Mat4
---@operator mul(pge.Vector): pge.Vec3
local Mat4 = {}
---@param p pge.Vector
---@return pge.Vec3
function Mat4:transformPoint(p) end
---@param v pge.Vector
---@return pge.Vec3
function Mat4:transformVector(v) end
---@return pge.Mat4
function Mat4:inverse() end
---@return pge.Vec3
function Mat4:position() end
---@param v pge.Vector
---@return pge.Mat4
function Mat4:translate(v) end
---@param axis pge.Vector|pge.Quat
---@param degrees? number
---@return pge.Mat4
function Mat4:rotate(axis, degrees) end
---@param s number|pge.Vector
---@return pge.Mat4
function Mat4:scale(s) end

pge.mat4 = {}
---@return pge.Mat4
function pge.mat4.identity() end
---@param v pge.Vector
---@return pge.Mat4
function pge.mat4.translate(v) end
---@param axis pge.Vector|pge.Quat
---@param degrees? number
---@return pge.Mat4
function pge.mat4.rotate(axis, degrees) end
---@param s number|pge.Vector
---@return pge.Mat4
function pge.mat4.scale(s) end

pge.noise = {}
---@return number
function pge.noise.perlin(x, y, z) end
---@return number
function pge.noise.simplex(x, y, z) end
---@param x number
---@param y number
---@param z? number|{octaves?: integer, frequency?: number, lacunarity?: number, persistence?: number, seed?: integer}
---@param options? {octaves?: integer, frequency?: number, lacunarity?: number, persistence?: number, seed?: integer}
---@return number
function pge.noise.fbm(x, y, z, options) end

---Runs another script (relative to this one) with parameter overrides; returns its value.
---@param path string
---@param params? table<string, number|boolean|string>
---@return any
function pge.load(path, params) end

---@class pge.Material
---@field color? string "#rrggbb" or "#rrggbbaa"
---@field doubleSided? boolean
---@field roughness? number
---@field metallic? number
---@field alpha? "opaque"|"mask"|"blend"
---@field alphaCutoff? number
---@field texture? string|pge.Image|pge.Texture a PNG path relative to the script, or anything with :pngBytes() (an image)
---@field name? string

---@class pge.Mesh
local Mesh = {}
---@return integer
function Mesh:vertexCount() end
---@return integer
function Mesh:triangleCount() end
---@return pge.Model
function Mesh:model() end

---@param spec {positions: number[], indices: integer[], normals?: number[], uvs?: number[], colors?: number[], primitive?: "triangles"|"lines", name?: string, material?: pge.Material}
---@return pge.Mesh
function pge.mesh(spec) end

---@class pge.Model
local Model = {}
---@param thing pge.Modelish|pge.AlgorithmHandle
---@param transform? pge.Mat4
function Model:add(thing, transform) end
---@return integer
function Model:vertexCount() end
---@return integer
function Model:triangleCount() end
---@return integer
function Model:meshCount() end
---@return integer
function Model:instanceCount() end
---Gives the model an equirectangular sky (row 0 straight up, the middle row the horizon):
---written to the glb as an image named by `extras.pge.environment`, drawn by the preview
---behind the model.
---@param image string|pge.Image|pge.Texture a PNG path relative to the script, or anything with :pngBytes()
function Model:setEnvironment(image) end
---@return pge.Model
function Model:model() end

---@return pge.Model
function pge.model() end

---@class pge.AlgorithmHandle
local AlgorithmHandle = {}
---Grows the algorithm to the end and returns its model.
---@return pge.Model
function AlgorithmHandle:model() end
---Grows the algorithm to the end and returns its branch skeleton (space colonization,
---growth, an L-system's turtle).
---@return pge.Skeleton
function AlgorithmHandle:skeleton() end
---@return string
function AlgorithmHandle:name() end

---A step-wise generator written in Lua.
---@param spec {init?: fun(self: table), step: fun(self: table): boolean, finish: fun(self: table): pge.Modelish}
---@return pge.AlgorithmHandle
function pge.Algorithm(spec) end
