---@meta
-- LuaLS annotations for L-systems (pge.LSystem, symbols, pge.sym) and the turtle
-- (pge.turtle). Reference: docs/lua-api.md, sections "L-systems" and "The turtle".

---A symbol: its own parameter table (positional `s[1]`, named `s.v`, any Lua values), tagged
---as the symbol `name` (the table given to the constructor, not a copy). Any undefined global
---starting with an uppercase ASCII letter is the constructor of the symbol of that name:
---`A{}`, `A()`, `Apex{age = 2}`, `F{1.5}`. Parameters must be one table (`A(5)` is an error).
---@class pge.Symbol: table
---@field name string the symbol's name (unless the table has its own `name` field)

---A successor: a symbol, a string in classic notation, or an array of these where a nested
---array is a branch (wrapped in `[` `]`). `{}` deletes the symbol; `nil` means "does not apply".
---@alias pge.Successor pge.Symbol|string|pge.Successor[]

---Builds any symbol, `[` and `+` included: `pge.sym("+", {30})`. The name must be non-empty
---and without spaces.
---@param name string
---@param params? table
---@return pge.Symbol
function pge.sym(name, params) end

---The instance of the running L-system (`createInstance`'s value, or a `pge.turtle{}`).
---Read-only during rewriting rules (RRules); IRules and callbacks may change it.
---@type any
this = nil

---An L-system object: a recipe copied into each run (`:algorithm()`, `:model()`, or
---returning it from the script). Its global table is shared with the runs.
---@class pge.LSystem
local LSystem = {}

---A new L-system. The name appears in errors (default "lsystem").
---@param name? string
---@return pge.LSystem
function pge.LSystem(name) end

---The starting string: classic notation with constant expressions (`"F(1) A"`) or an array
---of symbols, strings and nested arrays (branches). Required.
---@param axiom string|pge.Successor
function LSystem:axiom(axiom) end

---Derivation steps, a whole number 0..1000000 (default 0). `--steps` overrides it, except
---for `:model()`.
---@param n integer
function LSystem:iterations(n) end

---The module cap, 0..4294967295 (default the engine's, 10 000 000); passing it stops the
---run with an error naming the step and the count.
---@param n integer
function LSystem:maxModules(n) end

---`false`: interpret only the final string (classic mode, faster). Default `true`.
---@param on boolean
function LSystem:interpretEveryStep(on) end

---The instance `this`: `f` is called once at the start of every run, drawing from the
---instance's generator. Default: `pge.turtle{}`.
---@param f fun(): any
function LSystem:createInstance(f) end

---Called before each step (after the instance's `reset` when interpreting every step); a
---non-nil return value replaces the instance from then on.
---@param f fun(): any
function LSystem:beforeStep(f) end

---Called after each step.
---@param f fun()
function LSystem:afterStep(f) end

---Sets a value of the global table; numbers are names classic expressions can read.
---An error during rewriting rules.
---@param key string
---@param value any
function LSystem:set(key, value) end

---A value of the global table.
---@param key string
---@return any
function LSystem:get(key) end

---Multi-letter module names for this object's classic strings, separated by spaces.
---@param names string
function LSystem:declare(names) end

---Symbols skipped when matching contexts, separated by spaces: `"+ - F"`.
---@param names string
function LSystem:ignore(names) end

---A classic production, compiled in Rust: `"A(l, w) : l > 0.1 -> F(l) [ +(30) A(l*0.7, w) ]"`,
---contexts `"b < a > c -> ..."` (`*`: none), arrow `->` or `-->`, empty successor deletes.
---Productions with the same left side and a weight are stochastic alternatives (weights
---normalised). A pattern `A(x)` meeting a module with another parameter count is an error.
---The fast path: write rules this way whenever arithmetic, contexts, conditions and `rand()`
---suffice.
---@param production string
---@param weight? number a finite number > 0
function LSystem:rule(production, weight) end

---A rewriting rule: `lhs` is `"S"`, `"L < S"`, `"S > R"` or `"L < S > R"` (symbols separated
---by spaces; the right context may hold `[` `]`; no `:` condition). `f` receives the
---parameter tables of the left side's symbols, leftmost first (brackets excluded); it returns
---a successor, `{}` to delete, or nil when it does not apply (the next rule is tried).
---For logic classic notation cannot express: one Lua call per module, about 0.5 µs each
---under the deterministic instruction limit (some 2 million modules a second).
---@param lhs string
---@param f fun(...: table): pge.Successor?
function LSystem:RRule(lhs, f) end

---An interpretation rule: `"S"` or `"L < S"` (`[` and `]` may be interpreted too). A left
---context is matched in the string interpreted so far; a right context is an error. `f`
---receives the parameter tables of the left context and of S, leftmost first, and applies
---when it returns a value other than nil and false; otherwise the next IRule, then the
---instance's default interpretation (a turtle's commands); a module nobody interprets is
---skipped.
---@param lhs string
---@param f fun(...: table): any
function LSystem:IRule(lhs, f) end

---The L-system as an algorithm (what returning the object from a script does).
---@return pge.AlgorithmHandle
function LSystem:algorithm() end

---Runs the L-system to the end (ignoring `--steps`) and returns the instance's model.
---@return pge.Model
function LSystem:model() end

---@return string
function LSystem:name() end

---@class pge.TurtleOptions
---@field angle? number degrees of `+ - & ^ \ /` without parameter (default 90)
---@field step? number length of `F` and `f` without parameter, >= 0 (default 1)
---@field width? number starting branch diameter, >= 0 (default 0.1)
---@field widthFactor? number `!` without parameter multiplies the width by this, >= 0 (default 0.7)
---@field tropism? pge.Vector after each `F` the heading turns toward it by elasticity * abs(H x T) radians
---@field elasticity? number susceptibility to tropism (default 0.2)
---@field leafSize? number size of `~` without parameter, >= 0 (default 0.25)
---@field sides? integer ring resolution of the bark mesh, 3..64 (default 8; wins over mesh.sides)
---@field mesh? pge.TreeMeshOptions bark options; `radii` defaults to "keep" (the turtle's widths)
---@field leaves? pge.LeafOptions tip leaves besides the `~` leaves (a table; not true/false)
---@field colors? string[] bark colour "#rrggbb" of each colour index `'`, cycling

---A 3D turtle recording branch skeletons; the default instance of an L-system. It starts
---at the origin heading +Y, left -X, up +Z. Its commands (default interpretation, first
---numeric parameter as argument): `F(l) f(l) +(a) -(a) &(a) ^(a) \(a) /(a) | [ ] !(w) '(i)
---$ ~(s)`; other names are skipped. Mutating methods are errors during an RRule.
---@class pge.Turtle
local Turtle = {}

---A turtle. An unknown option is an error listing the known ones.
---@param options? pge.TurtleOptions
---@return pge.Turtle
function pge.turtle(options) end

---`F`: forward drawing a branch segment (`step` without argument).
---@param length? number
function Turtle:forward(length) end
---`f`: forward without drawing; the next segment starts a new branch.
---@param length? number
function Turtle:move(length) end
---`+`: yaw left about the up vector (negative: right, as `-`).
---@param degrees? number
function Turtle:turn(degrees) end
---`&`: pitch down about the left vector (negative: up, as `^`).
---@param degrees? number
function Turtle:pitch(degrees) end
---`\`: roll left about the heading (negative: right, as `/`).
---@param degrees? number
function Turtle:roll(degrees) end
---`|`: turn 180 degrees about the up vector.
function Turtle:turnAround() end
---`[`: save the state; the branch's order is one more.
function Turtle:push() end
---`]`: restore the state saved by the matching `[` (an error without one).
function Turtle:pop() end
---`!`: sets the width (>= 0); without argument multiplies it by widthFactor.
---@param width? number
function Turtle:setWidth(width) end
---`'`: sets the colour index (>= 0, rounded); without argument adds one. Each index is its
---own skeleton and mesh.
---@param index? integer
function Turtle:setColor(index) end
---`$`: roll so that the left vector is horizontal.
function Turtle:rollToHorizontal() end
---`~`: a leaf of size `size` (>= 0) hung where the turtle stands, along its heading.
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
---The current width (diameter).
---@return number
function Turtle:width() end
---Skeleton nodes drawn so far.
---@return integer
function Turtle:nodes() end
---What the turtle drew, every colour's branches in one skeleton.
---@return pge.Skeleton
function Turtle:skeleton() end
---Back to the start, forgetting what was drawn.
function Turtle:reset() end
---The bark (and leaf) meshes of what was drawn.
---@return pge.Model
function Turtle:model() end
