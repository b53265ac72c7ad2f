---@meta
-- LuaLS annotations for pge.LSystem and symbols (plugin pge-lsystem).
-- Add this folder next to docs/lua in "workspace.library" of .luarc.json.

---A symbol: its own parameter table (positional `s[1]`, named `s.v`, any Lua values),
---tagged as the symbol `name`. Any undefined global starting with an uppercase ASCII letter
---is the constructor of the symbol of that name: `A{}`, `Apex{age = 2}`, `F{1.5}`.
---@class pge.Symbol: table
---@field name string

---A successor: a symbol, a string in classic notation, or an array of these where a nested
---array is a branch (wrapped in `[` `]`). `{}` deletes the symbol.
---@alias pge.Successor pge.Symbol|string|pge.Successor[]

---Builds any symbol, `[` and `+` included.
---@param name string
---@param params? table
---@return pge.Symbol
function pge.sym(name, params) end

---The instance of the running L-system (`createInstance`'s value, or a `pge.turtle{}`).
---Read-only during rewriting rules.
---@type any
this = nil

---@class pge.LSystem
local LSystem = {}

---A new L-system.
---@param name? string
---@return pge.LSystem
function pge.LSystem(name) end

---The starting string: classic notation or an array of symbols.
---@param axiom string|pge.Successor
function LSystem:axiom(axiom) end

---Derivation steps (`--steps` overrides). Default 0.
---@param n integer
function LSystem:iterations(n) end

---The module cap (default 10 000 000); passing it stops the run with an error.
---@param n integer
function LSystem:maxModules(n) end

---`false`: interpret only after the last step (classic mode, faster).
---@param on boolean
function LSystem:interpretEveryStep(on) end

---The instance `this` (called once per run, drawing from the instance's generator).
---@param f fun(): any
function LSystem:createInstance(f) end

---Called before each step; a returned value becomes `this` for the step.
---@param f fun(): any
function LSystem:beforeStep(f) end

---Called after each step.
---@param f fun()
function LSystem:afterStep(f) end

---Sets a value of the global table (numbers are readable in classic expressions).
---Read-only during rewriting rules.
---@param key string
---@param value any
function LSystem:set(key, value) end

---A value of the global table.
---@param key string
---@return any
function LSystem:get(key) end

---Multi-letter module names for the classic notation, separated by spaces.
---@param names string
function LSystem:declare(names) end

---Symbols skipped when matching contexts, separated by spaces: `"+ - F"`.
---@param names string
function LSystem:ignore(names) end

---A classic production, compiled in Rust: `"A(l,w) : l > 0.1 -> F(l)[+(30)A(l*0.7,w)]"`,
---contexts `"b < a > c -> ..."`. Productions with the same left side and a weight are
---stochastic alternatives (weights normalised).
---@param production string
---@param weight? number
function LSystem:rule(production, weight) end

---A rewriting rule: `lhs` is `"S"`, `"L < S"`, `"S > R"` or `"L < S > R"` (symbols separated
---by spaces; the right context may hold `[` `]`). `f` receives the parameter tables of the
---left side's symbols, leftmost first; nil: does not apply; `{}`: deletes.
---@param lhs string
---@param f fun(...: table): pge.Successor?
function LSystem:RRule(lhs, f) end

---An interpretation rule: `"S"` or `"L < S"` (`[` and `]` may be interpreted too; a left
---context is matched in the string interpreted so far; no right context). `f` receives the
---parameter tables, leftmost first, and applies when it returns a value other than nil and
---false; otherwise the next IRule, then the instance's default interpretation (a turtle's
---commands).
---@param lhs string
---@param f fun(...: table): any
function LSystem:IRule(lhs, f) end

---The L-system as an algorithm (what returning the object from a script does).
---@return pge.AlgorithmHandle
function LSystem:algorithm() end

---Runs the L-system to the end and returns the instance's model.
---@return pge.Model
function LSystem:model() end

---@return string
function LSystem:name() end
