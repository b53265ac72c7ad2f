---@meta
-- LuaLS annotations for pge.turtle (plugin pge-turtle).
-- Add this folder next to docs/lua in "workspace.library" of .luarc.json.

---@class pge.TurtleOptions
---@field angle? number degrees of `+ - & ^ \ /` without parameter (default 90)
---@field step? number length of `F` and `f` without parameter (default 1)
---@field width? number starting branch diameter (default 0.1)
---@field widthFactor? number `!` without parameter multiplies the width by this (default 0.7)
---@field tropism? pge.Vector the heading bends toward it after each `F`
---@field elasticity? number susceptibility to tropism (default 0.2)
---@field sides? integer ring resolution of the bark mesh (3..64, default 8)
---@field leaves? table tip leaves: {perTip = {min, max}, size, colors, maxDepth, texture}
---@field leafSize? number size of `~` without parameter (default 0.25)
---@field mesh? table bark mesh options (sides, caps, radii = "keep"|"pipe", color, ...)
---@field colors? string[] bark colour of each colour index `'` ("#rrggbb")

---A 3D turtle recording a branch skeleton; the default instance of an L-system. It starts
---at the origin heading +Y. Its commands (default interpretation): `F(l) f(l) +(a) -(a)
---&(a) ^(a) \(a) /(a) | [ ] !(w) '(i) $ ~(s)`.
---@class pge.Turtle
local Turtle = {}

---@param options? pge.TurtleOptions
---@return pge.Turtle
function pge.turtle(options) end

---`F`: forward drawing a branch segment.
---@param length? number
function Turtle:forward(length) end
---`f`: forward without drawing.
---@param length? number
function Turtle:move(length) end
---`+` (left) / `-` (negative): about the up vector.
---@param degrees? number
function Turtle:turn(degrees) end
---`&` (down) / `^` (negative): about the left vector.
---@param degrees? number
function Turtle:pitch(degrees) end
---`\` (left) / `/` (negative): about the heading.
---@param degrees? number
function Turtle:roll(degrees) end
---`|`
function Turtle:turnAround() end
---`[`
function Turtle:push() end
---`]`
function Turtle:pop() end
---`!`: sets the width; without argument multiplies it by widthFactor.
---@param width? number
function Turtle:setWidth(width) end
---`'`: sets the colour index; without argument adds one.
---@param index? integer
function Turtle:setColor(index) end
---`$`
function Turtle:rollToHorizontal() end
---`~`: a leaf hung where the turtle stands.
---@param size? number
function Turtle:leaf(size) end
---@return pge.Vec3
function Turtle:position() end
---@return pge.Vec3
function Turtle:heading() end
---@return pge.Vec3
function Turtle:left() end
---@return pge.Vec3
function Turtle:up() end
---@return number
function Turtle:width() end
---Skeleton nodes drawn so far.
---@return integer
function Turtle:nodes() end
---Back to the start, forgetting what was drawn.
function Turtle:reset() end
---The bark (and leaf) meshes of what was drawn.
---@return pge.Model
function Turtle:model() end
