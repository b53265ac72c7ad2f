---@meta
-- LuaLS annotations for the thesis' modellers: pge.Extruder, pge.MatrixManipulator,
-- pge.Metaballs, pge.MarchingCubes, pge.Lines and pge.Image. Reference: docs/lua-api.md.
-- Mutating methods are errors inside an L-system's rewriting rule (RRule).

---A colour: "#rrggbb", "#rrggbbaa", or {r, g, b [, a]} in [0, 1] (sRGB).
---@alias pge.Colour string|number[]

---A 4x4 transform with a stack; every operation multiplies on the right (local frame).
---Angles in degrees.
---@class pge.MatrixManipulator
local MatrixManipulator = {}

---@return pge.MatrixManipulator
function pge.MatrixManipulator() end

---Saves the matrix (at most 65536 deep).
function MatrixManipulator:push() end
---Restores the matrix saved by the last push (an error without one).
function MatrixManipulator:pop() end
---The identity; the stack is kept.
function MatrixManipulator:reset() end
---A rotation about `axis` (a vector, or three numbers: `rotate(90, 0, 0, 1)`); degrees first.
---A zero axis is an error.
---@param degrees number
---@param axis pge.Vector|number
---@param y? number
---@param z? number
function MatrixManipulator:rotate(degrees, axis, y, z) end
---@param degrees number
function MatrixManipulator:rotateX(degrees) end
---@param degrees number
function MatrixManipulator:rotateY(degrees) end
---@param degrees number
function MatrixManipulator:rotateZ(degrees) end
---`scale(s)`, `scale(x, y, z)` or `scale(v)`; zero factors are allowed.
---@param s number|pge.Vector
---@param y? number
---@param z? number
function MatrixManipulator:scale(s, y, z) end
---@param f number
function MatrixManipulator:scaleX(f) end
---@param f number
function MatrixManipulator:scaleY(f) end
---@param f number
function MatrixManipulator:scaleZ(f) end
---`translate(x, y, z)` or `translate(v)`, in the local frame.
---@param x number|pge.Vector
---@param y? number
---@param z? number
function MatrixManipulator:translate(x, y, z) end
---`translate(0, d, 0)`: along the extrusion axis.
---@param d number
function MatrixManipulator:advance(d) end
---@return pge.Mat4
function MatrixManipulator:getMatrix() end
---Replaces the matrix (the stack is kept).
---@param m pge.Mat4
function MatrixManipulator:setMatrix(m) end
---@param x number|pge.Vector
---@param y? number
---@param z? number
---@return pge.Vec3
function MatrixManipulator:transformPoint(x, y, z) end
---The frame's origin.
---@return pge.Vec3
function MatrixManipulator:position() end
---Pushes not yet popped.
---@return integer
function MatrixManipulator:depth() end

---@class pge.ExtruderOptions
---@field smooth? boolean normals averaged around the tube (false: one per quad)
---@field caps? boolean close both ends of every piece (true)
---@field color? string the material's base colour "#rrggbb"
---@field material? pge.Material

---A 2D shape in the local XZ plane swept along the path matrix's +Y axis; a shape point s
---lands at `path * shapeMatrix * s`.
---@class pge.Extruder
local Extruder = {}

---An extruder; an unknown option is an error.
---@param options? pge.ExtruderOptions
---@return pge.Extruder
function pge.Extruder(options) end

---A shape point in the local XZ plane: `addPoint2(x, z)` or `addPoint2{x, z}`.
---@param x number|number[]
---@param z? number
function Extruder:addPoint2(x, z) end
---A 3D shape point: `addPoint3(x, y, z)` or `addPoint3(v)`.
---@param x number|pge.Vector
---@param y? number
---@param z? number
function Extruder:addPoint3(x, y, z) end
---Empties the shape.
function Extruder:clearShape() end
---Replaces the shape by a regular n-gon (n >= 3) of circumradius r, counter-clockwise from +Y.
---@param sides integer
---@param radius number
function Extruder:polygon(sides, radius) end
---@return integer
function Extruder:pointCount() end
---Extrudes the shape (at least 3 points) `distance` (>= 0) along the path's local +Y axis;
---consecutive extrusions form one tube.
---@param distance number
function Extruder:extrude(distance) end
---The extruder's path matrix (live).
---@return pge.MatrixManipulator
function Extruder:getPathMatrix() end
---The extruder's shape matrix (live).
---@return pge.MatrixManipulator
function Extruder:getShapeMatrix() end
---Saves path, shape matrix, shape and colour and opens a new piece (a branch).
function Extruder:push() end
---Closes the piece opened by the last push and restores its state (an error without one).
function Extruder:pop() end
---Ends the current piece (with caps).
function Extruder:start() end
---Ends the current piece (with caps).
function Extruder:finish() end
---Vertex colour "#rrggbb" of the rings placed from now on.
---@param colour string
function Extruder:setColor(colour) end
---The path's origin.
---@return pge.Vec3
function Extruder:position() end
---Everything extruded so far (open pieces included).
---@return pge.Mesh
function Extruder:mesh() end
---@return pge.Model
function Extruder:model() end
---The thesis' name for `model()`.
---@return pge.Model
function Extruder:getNode() end

---@class pge.Particle
---@field position pge.Vec3
---@field charge number
---@field radius number

---A field of charged particles: sum of q (1 - d^2/R^2)^3 within each particle's radius R.
---@class pge.Metaballs
local Metaballs = {}

---A field; `radius` (> 0, default 1) is the default radius of influence.
---@param options? {radius?: number}
---@return pge.Metaballs
function pge.Metaballs(options) end

---Adds a particle (charge default 1, negative carves; radius > 0, default the field's);
---returns its number from 1.
---@param position pge.Vector
---@param charge? number
---@param radius? number
---@return integer
function Metaballs:addParticle(position, charge, radius) end
---The field's value at p.
---@param p pge.Vector
---@return number
function Metaballs:calc(p) end
---@param p pge.Vector
---@return pge.Vec3
function Metaballs:gradient(p) end
---Particle i, from 1 to count().
---@param i integer
---@return pge.Particle
function Metaballs:getParticle(i) end
---@return integer
function Metaballs:count() end
---Recomputes the bounds (done lazily anyway).
function Metaballs:update() end
---The box outside which the field is zero; nil, nil without particles.
---@return pge.Vec3? min
---@return pge.Vec3? max
function Metaballs:bounds() end

---@class pge.MarchingCubesOptions
---@field resolution? integer cells along the longest side of the bounds, 1..4096 (64)
---@field iso? number the surface's field value, > 0 (0.5)
---@field bounds? {min: pge.Vector, max: pge.Vector}|pge.Vector[] the box sampled (where any particle reaches)
---@field maxCells? integer the most cells of the grid, >= 1 (2^31)
---@field color? string "#rrggbb", over material
---@field material? pge.Material

---Extracts a field's isosurface when its mesh or model is asked for (later particles included).
---@class pge.MarchingCubes
local MarchingCubes = {}

---@param meta pge.Metaballs
---@param options? pge.MarchingCubesOptions
---@return pge.MarchingCubes
function pge.MarchingCubes(meta, options) end
---@return pge.Mesh
function MarchingCubes:mesh() end
---@return pge.Model
function MarchingCubes:model() end

---Coloured 3D segments, exported as a glTF line mesh with vertex colours, or with a
---`width` as thin tubes (triangles) that every client renders.
---@class pge.Lines
local Lines = {}

---@param options? {color?: pge.Colour, width?: number} the default colour (white); the tube width in metres (0, the default: glTF lines)
---@return pge.Lines
function pge.Lines(options) end
---The segment a-b.
---@param a pge.Vector
---@param b pge.Vector
---@param colour? pge.Colour
function Lines:add(a, b, colour) end
---@return integer
function Lines:count() end
function Lines:clear() end
---@return pge.Mesh
function Lines:mesh() end
---@return pge.Model
function Lines:model() end

---A snapshot of an image as a texture; a material's `texture` may be one.
---@class pge.Texture
local Texture = {}
---@return integer
function Texture:width() end
---@return integer
function Texture:height() end
---@return string
function Texture:pngBytes() end

---An RGBA8 sRGB picture; pixel coordinates are 0-based whole numbers, row 0 at the top.
---@class pge.Image
local Image = {}

pge.Image = {}
---A new image (w, h >= 1, at most 2^28 pixels), filled with `fill` (opaque black).
---@param w integer
---@param h integer
---@param fill? pge.Colour
---@return pge.Image
function pge.Image.new(w, h, fill) end
---Loads an image file relative to the script.
---@param path string
---@return pge.Image
function pge.Image.load(path) end

---@return integer
function Image:width() end
---@return integer
function Image:height() end
---Whether (x, y) is a pixel of the image.
---@param x number
---@param y number
---@return boolean
function Image:inside(x, y) end
---r, g, b, a in [0, 1].
---@param x integer
---@param y integer
---@return number r
---@return number g
---@return number b
---@return number a
function Image:get(x, y) end
---"#rrggbb", or "#rrggbbaa" when not opaque.
---@param x integer
---@param y integer
---@return string
function Image:getHex(x, y) end
---`set(x, y, colour)` or `set(x, y, r, g, b [, a])`.
---@param x integer
---@param y integer
---@param colour pge.Colour|number
---@param g? number
---@param b? number
---@param a? number
function Image:set(x, y, colour, g, b, a) end
---@param colour pge.Colour
function Image:fill(colour) end
---Writes a PNG; a relative path without `..`, from the working directory.
---@param path string
function Image:save(path) end
---@return pge.Image
function Image:clone() end
---@return pge.Texture
function Image:texture() end
---@return string
function Image:pngBytes() end
---A copy of `thing` whose materials use the image as their texture.
---@param thing pge.Modelish
---@return pge.Model
function Image:applyTo(thing) end
---A textured quad over [0, w] x [0, h] in the XZ plane, facing +Y.
---@return pge.Model
function Image:model() end
