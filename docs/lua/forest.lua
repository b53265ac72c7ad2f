---@meta
-- LuaLS annotations for forests (pge.Forest). Reference: docs/lua-api.md, section "Forests".

---@class pge.ForestOptions
---@field size? number|{[1]: number, [2]: number} metres, x by z (default {500, 500}), > 0
---@field seed? integer the forest's seed (default: the run's --seed)
---@field tile? number side of a tile in metres (> 0): `pge run --tile I,J` writes one

---@class pge.TerrainOptions
---@field height? number fBm amplitude, or the height of white in an image (metres)
---@field scale? number fBm: size of the largest hills in metres (> 0, default 300)
---@field octaves? integer fBm octaves, 1..16 (default 5)
---@field lacunarity? number fBm frequency factor (> 0, default 2)
---@field persistence? number fBm amplitude factor (> 0, default 0.5)
---@field image? string a greyscale PNG height map, relative to the script
---@field resolution? number metres between terrain vertices (> 0, default 4)

---@class pge.ScatterOptions
---@field species string|fun(params: table, seed: integer): any a species script or a function returning a tree
---@field minDistance number metres between trunks of this layer and from earlier layers (> 0)
---@field method? "poisson"|"jittered"
---@field jitter? number jittered grid only: fraction of the cell, [0, 0.5) (default 0.2)
---@field density? number|string|fun(x: number, z: number): number 0..1, a PNG map or a function
---@field slope? {[1]: number, [2]: number} degrees {min, max}
---@field altitude? {[1]: number, [2]: number} metres {min, max}
---@field variants? integer|"unique" meshes grown per species (default 8)
---@field scale? {[1]: number, [2]: number} per-instance scale {min, max}
---@field params? table overrides of the species script's parameters

---@class pge.ForestInstance
---@field species string
---@field variant integer from 0, as in the mesh name SPECIES/VARIANT
---@field position pge.Vec3
---@field yaw number degrees
---@field scale number

---@class pge.ForestTile
---@field i integer
---@field j integer
---@field min {[1]: number, [2]: number}
---@field max {[1]: number, [2]: number}

---A forest: a terrain and species layers. Return it from a script to generate it.
---@class pge.Forest
local Forest = {}
---Sets the terrain (fBm noise, or `image = "h.png"`).
---@param o pge.TerrainOptions
---@return pge.Forest
function Forest:terrain(o) end
---Adds a layer of one species.
---@param o pge.ScatterOptions
---@return pge.Forest
function Forest:scatter(o) end
---The terrain height at (x, z).
---@param x number
---@param z number
---@return number
function Forest:height(x, z) end
---The terrain's unit normal at (x, z).
---@param x number
---@param z number
---@return pge.Vec3
function Forest:normal(x, z) end
---Every tree of the forest (or of the selected tile).
---@return pge.ForestInstance[]
function Forest:instances() end
---The tiles of a forest with `tile`.
---@return pge.ForestTile[]
function Forest:tiles() end
---Generate tile (i, j) alone.
---@param i integer
---@param j integer
---@return pge.Forest
function Forest:selectTile(i, j) end

---A new forest.
---@param o pge.ForestOptions
---@return pge.Forest
function pge.Forest(o) end
