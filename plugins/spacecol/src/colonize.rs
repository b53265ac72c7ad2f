//! Space colonization (Runions, Lane and Prusinkiewicz 2007; seeds 000 ch. 2 and 002) as a
//! step-wise [`Algorithm`].
//!
//! Each step is one iteration: every attraction point pulls the node nearest to it (within
//! the influence radius); each pulled node grows one segment of length `step` along
//! `normalize(normalize(sum of unit vectors) + tropism)`; points within the kill distance
//! of a node are removed. Before a root's node is within reach of any point, that root grows
//! a trunk toward the cloud (the sum of unit vectors to all points, seed 000).
//!
//! Free growth has no memory: a tip follows whatever pulls it, so a branch that has passed
//! its points follows the points still beside or above it and can curl back (a conifer's
//! lower branches follow the cone up toward the leader). Three options, all off by default,
//! hold a branch's course: direction persistence (the tip's own direction added to the
//! pull), an angle of perception (a tip sees only points ahead of it; Runions et al.), and a
//! bound on how far a branch may turn from the direction it started in.
//!
//! Cost: a point's nearest node only changes when a node is added closer to it, so each
//! point keeps its nearest node and its distance to it (its *reach*), and a new node visits
//! only the points it changes: those within the influence radius and closer to it than to
//! their nearest node (or within the kill distance). The [`PointGrid`] (cells of a third
//! of the influence radius, split again where points are dense) keeps the largest reach of
//! each cell and sub-cell, and a new node skips, unread, every cell whose distance exceeds
//! that bound. An iteration then costs O(attracted points + the points each new node
//! changes + the cells around it), not points x nodes nor new nodes x points in reach.
//!
//! The known failure of the method, a node pulled by points on opposite sides (its sum of
//! directions cancels) or one that keeps regrowing where a node already stands, is guarded:
//! a cancelled sum grows toward the closest attracting point instead, and a growth that
//! would land within a fifth of a step of an existing node is refused and the points pulling
//! that node are dropped as unreachable. Every iteration therefore adds a node or removes a
//! point, and the iteration cap bounds the rest (with a warning).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::time::Instant;

use glam::Vec3;
use pge_engine::geometry::{Model, Skeleton};
use pge_engine::{Algorithm, Error, Location, Result, RunContext, Step};
use pge_tree::TreeOptions;

use crate::points::{self, Mode, PointGrid};
use crate::shape::Shape;

/// The parameters of a colonization (API.md §5).
#[derive(Clone, Debug)]
pub struct Params {
    /// Where the attraction points are.
    pub envelope: Shape,
    /// How many points (`None`: [`points::DEFAULT_POINTS`], or every vertex in the
    /// `vertices` mode).
    pub points: Option<u32>,
    /// How points are taken from the envelope.
    pub mode: Mode,
    /// Influence radius: a point pulls its nearest node only within this distance.
    pub influence: f32,
    /// Kill distance: a point this close to a node is removed (must be < `influence`).
    pub kill: f32,
    /// Segment length D.
    pub step: f32,
    /// Tropism g added to each unit growth direction (e.g. `(0, -0.3, 0)` for weeping).
    pub tropism: Vec3,
    /// Root positions (several for a bush).
    pub roots: Vec<Vec3>,
    /// Direction persistence w: a node grows along `normalize(pull + w * d)`, where `pull`
    /// is the unit mean of its attractions and `d` the direction of its own segment, before
    /// tropism is added (0 by default: the pull alone, seed 000).
    pub persistence: f32,
    /// Angle of perception in degrees: a branch tip is pulled only by points within this
    /// angle of its own direction, so it does not chase points beside or behind it (180 by
    /// default: every point). Nodes that already have a child sprout side branches toward
    /// any point.
    pub perception: f32,
    /// Largest turn in degrees of a branch from the direction it started in: a step that
    /// would turn further is clamped to this angle (180 by default: unbounded). A branch
    /// continues through a node's first child; later children start branches of their own.
    pub max_turn: f32,
    /// Length of a straight vertical trunk each root grows before anything else may pull
    /// it (0 by default). Lower points meanwhile pull the trunk's nodes into side branches,
    /// so a long trunk through the crown gives a central leader (a conifer).
    pub trunk: f32,
    /// Iteration cap; reaching it stops with a warning.
    pub max_iterations: u32,
    /// Mixed into the run's seed, so one script can grow several different trees (forest
    /// variants) in one run; 0 by default.
    pub seed: u64,
    /// Bark and leaf options.
    pub tree: TreeOptions,
    /// A skeleton grown by another method to grow on from (`start = skeleton`): its nodes
    /// come first, unchanged, in the result; its tips grow toward the points, its other
    /// nodes only take the points within the kill distance. `roots` and `trunk` are then
    /// unused.
    pub start: Option<std::sync::Arc<Skeleton>>,
}

impl Params {
    /// Parameters with defaults scaled to the envelope: `step` 1/50 of its bounds' diagonal,
    /// `influence` 8 steps, `kill` 2 steps, one root at the origin, 1000 iterations.
    #[must_use]
    pub fn new(envelope: Shape) -> Params {
        let (lo, hi) = envelope.bounds();
        let diag = (hi - lo).length();
        let step = if diag.is_finite() && diag > 0.0 {
            diag / 50.0
        } else {
            0.1
        };
        Params {
            envelope,
            points: None,
            mode: Mode::Fill,
            influence: 8.0 * step,
            kill: 2.0 * step,
            step,
            tropism: Vec3::ZERO,
            persistence: 0.0,
            perception: 180.0,
            max_turn: 180.0,
            roots: vec![Vec3::ZERO],
            trunk: 0.0,
            max_iterations: 1000,
            seed: 0,
            tree: TreeOptions::default(),
            start: None,
        }
    }

    /// Checks the ranges: an error names the parameter and what it needs.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be a number > 0, got {v}"))
            }
        };
        positive("step", self.step)?;
        positive("influence", self.influence)?;
        positive("kill", self.kill)?;
        if self.kill >= self.influence {
            return Err(format!(
                "kill ({}) must be smaller than influence ({}): points would be removed before they attract",
                self.kill, self.influence
            ));
        }
        if !(self.persistence.is_finite() && self.persistence >= 0.0) {
            return Err(format!(
                "persistence must be a number >= 0, got {}",
                self.persistence
            ));
        }
        for (name, v) in [("perception", self.perception), ("maxTurn", self.max_turn)] {
            if !(v.is_finite() && v > 0.0 && v <= 180.0) {
                return Err(format!(
                    "{name} must be an angle in degrees > 0 and <= 180, got {v}"
                ));
            }
        }
        if !(self.trunk.is_finite() && self.trunk >= 0.0) {
            return Err(format!("trunk must be a number >= 0, got {}", self.trunk));
        }
        if !self.tropism.is_finite() {
            return Err("tropism must be a finite vector".into());
        }
        if self.roots.is_empty() || self.roots.iter().any(|r| !r.is_finite()) {
            return Err("root must be a finite vector (roots: a non-empty list of them)".into());
        }
        if let Mode::Surround { thickness } = self.mode {
            positive("thickness", thickness)?;
        }
        if self.mode != Mode::Vertices
            && let Some(why) = self.envelope.open_mesh()
        {
            return Err(format!(
                "envelope: {why}; the inside test needs a closed mesh (or use mode = \"vertices\")"
            ));
        }
        if self.max_iterations == 0 {
            return Err("maxIterations must be an integer >= 1, got 0".into());
        }
        if let Some(start) = &self.start {
            pge_tree::check_skeleton(start).map_err(|e| format!("start: {e}"))?;
            if start.is_empty() {
                return Err("start must be a skeleton with nodes, got an empty one".into());
            }
        }
        Ok(())
    }
}

const NONE: u32 = u32::MAX;

/// The growing state.
#[derive(Clone)]
struct State {
    points: Vec<Vec3>,
    alive: Vec<bool>,
    alive_count: usize,
    nearest: Vec<u32>,
    nearest_d2: Vec<f32>,
    /// Points with a nearest node within reach (some may be dead; filtered each step).
    active: Vec<u32>,
    grid: PointGrid,
    dead_since_grid: usize,
    nodes: Vec<Vec3>,
    parents: Vec<Option<u32>>,
    /// Unit direction of each node's segment (zero for a root).
    dirs: Vec<Vec3>,
    /// Unit direction each node's branch started in (zero for a root).
    headings: Vec<Vec3>,
    /// Whether a node has grown a child.
    has_child: Vec<bool>,
    /// Nodes by cell of side `step`, for the duplicate-growth guard.
    node_cells: HashMap<[i32; 3], Vec<u32>, BuildHasherDefault<CellHasher>>,
    /// The iteration in which a node's growth was refused (its pullers are dropped next).
    refused: Vec<u32>,
    /// Roots still growing their trunk: the trunk's current tip and the length of straight
    /// trunk it must still grow.
    trunk_tips: Vec<(u32, f32)>,
    iteration: u32,
    // Per-step scratch.
    sum: Vec<Vec3>,
    count: Vec<u32>,
    closest: Vec<(f32, u32)>,
    touched: Vec<u32>,
}

/// Space colonization as an [`Algorithm`]: one step is one growth iteration; `finish` meshes
/// the current skeleton with [`pge_tree::build_tree`].
#[derive(Clone)]
pub struct SpaceColonization {
    params: Params,
    location: Location,
    state: Option<State>,
    done: bool,
    points_seconds: f64,
    growth_seconds: f64,
    warnings: Vec<String>,
}

impl SpaceColonization {
    /// A colonization with checked parameters; `location` is where script errors point
    /// (the constructor call).
    pub fn new(params: Params, location: Location) -> Result<SpaceColonization> {
        params
            .validate()
            .map_err(|m| Error::script(location.clone(), m))?;
        Ok(SpaceColonization {
            params,
            location,
            state: None,
            done: false,
            points_seconds: 0.0,
            growth_seconds: 0.0,
            warnings: Vec::new(),
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Warnings so far (the iteration cap).
    #[must_use]
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The branch skeleton grown so far (radii and orders unset, but for a start
    /// skeleton's nodes, which keep theirs and its leaf points), or `None` before `init`.
    #[must_use]
    pub fn skeleton(&self) -> Option<Skeleton> {
        let st = self.state.as_ref()?;
        let mut s = Skeleton::new();
        for (p, parent) in st.nodes.iter().zip(&st.parents) {
            s.push(*p, *parent, 0.0, 0);
        }
        if let Some(start) = &self.params.start {
            let n = start.len().min(s.len());
            s.radii[..n].copy_from_slice(&start.radii[..n]);
            s.orders[..n].copy_from_slice(&start.orders[..n]);
            s.leaves.clone_from(&start.leaves);
        }
        Some(s)
    }

    /// The attraction points and whether each is still alive, or `None` before `init`.
    #[must_use]
    pub fn attraction_points(&self) -> Option<(&[Vec3], &[bool])> {
        self.state.as_ref().map(|s| (&s.points[..], &s.alive[..]))
    }

    /// Whether the algorithm has stopped.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.done
    }

    /// Iterations taken.
    #[must_use]
    pub fn iterations(&self) -> u32 {
        self.state.as_ref().map_or(0, |s| s.iteration)
    }
}

impl State {
    /// Appends a node (its per-node scratch and its cell) without touching the points.
    fn push_node(&mut self, position: Vec3, parent: Option<u32>, p: &Params) -> u32 {
        let index = self.nodes.len() as u32;
        let dir = parent.map_or(Vec3::ZERO, |q| {
            (position - self.nodes[q as usize]).normalize_or_zero()
        });
        // The first child continues its parent's branch, later ones start their own.
        let heading = match parent.map(|q| q as usize) {
            Some(q) if !self.has_child[q] && self.headings[q] != Vec3::ZERO => self.headings[q],
            _ => dir,
        };
        if let Some(q) = parent {
            self.has_child[q as usize] = true;
        }
        self.nodes.push(position);
        self.parents.push(parent);
        self.dirs.push(dir);
        self.headings.push(heading);
        self.has_child.push(false);
        self.refused.push(NONE);
        self.sum.push(Vec3::ZERO);
        self.count.push(0);
        self.closest.push((f32::INFINITY, NONE));
        self.node_cells
            .entry(cell_of(position, p.step))
            .or_default()
            .push(index);
        index
    }

    /// Adds a node and updates the points it changes: those within the kill distance die,
    /// those within the influence radius that are closer to it than to their nearest node
    /// take it as their nearest. The grid skips every other point without reading it (a
    /// point's reach is its squared distance to its nearest node).
    fn add_node(&mut self, position: Vec3, parent: Option<u32>, p: &Params) -> u32 {
        let index = self.push_node(position, parent, p);
        let k2 = p.kill * p.kill;
        let State {
            grid,
            alive,
            alive_count,
            nearest,
            nearest_d2,
            active,
            dead_since_grid,
            ..
        } = self;
        grid.update_near(position, p.influence, |i, d2| {
            let i = i as usize;
            if !alive[i] {
                return 0.0;
            }
            if d2 < k2 {
                alive[i] = false;
                *alive_count -= 1;
                *dead_since_grid += 1;
                return 0.0;
            }
            if d2 < nearest_d2[i] {
                if nearest[i] == NONE {
                    active.push(i as u32);
                }
                nearest[i] = index;
                nearest_d2[i] = d2;
            }
            nearest_d2[i]
        });
        index
    }

    /// Whether a live point lies within the influence radius of `q` (and outside the kill
    /// distance, as after a node at `q` was added).
    fn in_range(&self, q: Vec3, p: &Params) -> bool {
        let k2 = p.kill * p.kill;
        let mut found = false;
        self.grid.for_each_near(q, p.influence, |i, _, d2| {
            found |= d2 >= k2 && self.alive[i as usize];
        });
        found
    }

    /// Seeds the nodes from a start skeleton (`start = skeleton`): every node in order;
    /// the tips attract points as grown nodes do, the other nodes only remove the points
    /// within the kill distance (they are wood already, not buds).
    fn seed_from(&mut self, start: &Skeleton, p: &Params) {
        let mut is_tip = vec![true; start.len()];
        for q in start.parents.iter().flatten() {
            is_tip[*q as usize] = false;
        }
        let k2 = p.kill * p.kill;
        for (i, &tip) in is_tip.iter().enumerate() {
            let position = start.positions[i];
            if tip {
                self.add_node(position, start.parents[i], p);
                continue;
            }
            self.push_node(position, start.parents[i], p);
            let State {
                grid,
                alive,
                alive_count,
                dead_since_grid,
                ..
            } = self;
            grid.for_each_near(position, p.kill, |j, _, d2| {
                let j = j as usize;
                if alive[j] && d2 < k2 {
                    alive[j] = false;
                    *alive_count -= 1;
                    *dead_since_grid += 1;
                }
            });
        }
    }

    /// Whether a node stands within `eps` of `q`.
    fn occupied(&self, q: Vec3, eps: f32, step: f32) -> bool {
        let c = cell_of(q, step);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = self.node_cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz])
                        && list
                            .iter()
                            .any(|n| self.nodes[*n as usize].distance_squared(q) < eps * eps)
                    {
                        return true;
                    }
                }
            }
        }
        false
    }

    fn kill(&mut self, i: usize) {
        if self.alive[i] {
            self.alive[i] = false;
            self.alive_count -= 1;
            self.dead_since_grid += 1;
        }
    }
}

/// The run's seed combined with a script's own `seed` (splitmix64 of the latter), the
/// identity for `seed = 0`.
fn mix(run: u64, own: u64) -> u64 {
    if own == 0 {
        return run;
    }
    let mut z = own.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    run ^ z ^ (z >> 31)
}

/// A fast hasher for integer cell keys (multiply-rotate, as rustc's FxHasher); the cell map
/// is only probed, never iterated, so its order cannot leak into the output.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(4) {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from(u32::from_le_bytes(word)));
        }
    }

    fn write_i32(&mut self, i: i32) {
        self.write_u64(i as u32 as u64);
    }

    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// `d` turned toward `heading` until the angle between them is at most the one whose cosine
/// and sine are given (both unit vectors; a zero heading bounds nothing).
fn clamp_turn(d: Vec3, heading: Vec3, cos: f32, sin: f32) -> Vec3 {
    if heading == Vec3::ZERO || d.dot(heading) >= cos {
        return d;
    }
    let side = (d - heading * d.dot(heading))
        .try_normalize()
        .unwrap_or_else(|| heading.any_orthonormal_vector());
    (heading * cos + side * sin).normalize_or_zero()
}

fn cell_of(p: Vec3, step: f32) -> [i32; 3] {
    let c = (p / step).floor();
    [c.x as i32, c.y as i32, c.z as i32]
}

impl Algorithm for SpaceColonization {
    fn name(&self) -> &str {
        "space colonization"
    }

    fn init(&mut self, ctx: &RunContext) -> Result<()> {
        let t = Instant::now();
        let p = &self.params;
        let pts = points::generate(
            &p.envelope,
            p.mode,
            p.points,
            mix(ctx.seed, self.params.seed) ^ 0x5ace_c010,
            ctx,
            &self.location,
        )?;
        let n = pts.len();
        let alive = vec![true; n];
        let grid = PointGrid::new(&pts, &alive, p.influence / 3.0);
        let mut st = State {
            points: pts,
            alive,
            alive_count: n,
            nearest: vec![NONE; n],
            nearest_d2: vec![f32::INFINITY; n],
            active: Vec::new(),
            grid,
            dead_since_grid: 0,
            nodes: Vec::new(),
            parents: Vec::new(),
            dirs: Vec::new(),
            headings: Vec::new(),
            has_child: Vec::new(),
            node_cells: HashMap::default(),
            refused: Vec::new(),
            trunk_tips: Vec::new(),
            iteration: 0,
            sum: Vec::new(),
            count: Vec::new(),
            closest: Vec::new(),
            touched: Vec::new(),
        };
        if let Some(start) = &p.start {
            st.seed_from(start, p);
        } else {
            for root in &p.roots {
                let r = st.add_node(*root, None, p);
                if p.trunk > 0.0 || !st.in_range(*root, p) {
                    st.trunk_tips.push((r, p.trunk));
                }
            }
        }
        self.state = Some(st);
        self.done = false;
        self.warnings.clear();
        self.points_seconds = t.elapsed().as_secs_f64();
        self.growth_seconds = 0.0;
        Ok(())
    }

    fn step(&mut self, ctx: &RunContext) -> Result<Step> {
        if self.done {
            return Ok(Step::Done);
        }
        let t = Instant::now();
        ctx.check_deadline(&self.location)?;
        let p = &self.params;
        let Some(st) = self.state.as_mut() else {
            return Err(Error::script(
                self.location.clone(),
                "space colonization stepped before init",
            ));
        };
        st.iteration += 1;
        let iteration = st.iteration;

        // Pulls: each live point adds its unit direction to its nearest node (a tip only
        // perceives the points within its angle of perception).
        let perceive = (p.perception < 180.0).then(|| p.perception.to_radians().cos());
        let mut active = std::mem::take(&mut st.active);
        active.retain(|&i| st.alive[i as usize]);
        for &i in &active {
            let i = i as usize;
            let n = st.nearest[i] as usize;
            if st.refused[n] == iteration - 1 {
                // The node could not grow toward these points last time: unreachable.
                st.kill(i);
                continue;
            }
            let d2 = st.nearest_d2[i];
            let to = (st.points[i] - st.nodes[n]) / d2.sqrt();
            if let Some(cos) = perceive
                && !st.has_child[n]
                && st.dirs[n] != Vec3::ZERO
                && to.dot(st.dirs[n]) < cos
            {
                continue;
            }
            if st.count[n] == 0 {
                st.touched.push(n as u32);
            }
            st.sum[n] += to;
            st.count[n] += 1;
            if d2 < st.closest[n].0 {
                st.closest[n] = (d2, i as u32);
            }
        }
        active.retain(|&i| st.alive[i as usize]);
        st.active = active;

        // Growth directions, all from the state before this iteration's new nodes.
        st.touched.sort_unstable();
        let max_turn = (p.max_turn < 180.0).then(|| p.max_turn.to_radians().sin_cos());
        let mut growth: Vec<(u32, Option<Vec3>, Option<f32>)> =
            Vec::with_capacity(st.touched.len() + st.trunk_tips.len());
        for &n in &st.touched {
            let n = n as usize;
            if st
                .trunk_tips
                .iter()
                .any(|&(tip, left)| tip as usize == n && left > 0.0)
            {
                // A straight trunk still growing is not pulled aside.
                st.sum[n] = Vec3::ZERO;
                st.count[n] = 0;
                st.closest[n] = (f32::INFINITY, NONE);
                continue;
            }
            let sum = st.sum[n];
            let dir = if sum.length() > 0.1 {
                sum.normalize()
            } else {
                (st.points[st.closest[n].1 as usize] - st.nodes[n]).normalize_or_zero()
            };
            let dir = if p.persistence > 0.0 {
                (dir + p.persistence * st.dirs[n]).normalize_or_zero()
            } else {
                dir
            };
            let dir = (dir + p.tropism).try_normalize().map(|d| match max_turn {
                // A later child starts a branch of its own: only a continuation is bounded.
                Some((sin, cos)) if !st.has_child[n] => clamp_turn(d, st.headings[n], cos, sin),
                _ => d,
            });
            growth.push((n as u32, dir, None));
            st.sum[n] = Vec3::ZERO;
            st.count[n] = 0;
            st.closest[n] = (f32::INFINITY, NONE);
        }
        st.touched.clear();

        // Trunks: straight up while a straight length is left, then toward the sum of unit
        // vectors to every live point until a point is within reach.
        // A tip is kept only while it has straight trunk left or no point in reach (checked
        // when it was added).
        let mut trunks = std::mem::take(&mut st.trunk_tips);
        if st.alive_count == 0 {
            trunks.clear();
        }
        for &(tip, left) in &trunks {
            if left > 0.0 {
                growth.push((tip, Some(Vec3::Y), Some(left - p.step)));
                continue;
            }
            let q = st.nodes[tip as usize];
            let mut sum = Vec3::ZERO;
            let mut closest = (f32::INFINITY, Vec3::ZERO);
            for (pt, alive) in st.points.iter().zip(&st.alive) {
                if *alive {
                    let d = *pt - q;
                    let l2 = d.length_squared();
                    if l2 > 0.0 {
                        sum += d / l2.sqrt();
                    }
                    if l2 < closest.0 {
                        closest = (l2, d);
                    }
                }
            }
            // Toward the cloud when it lies to one side; from inside a hollow cloud (the
            // unit vectors cancel) toward the nearest point. Tropism may bend the trunk but
            // not turn it away from that point, so the trunk always comes closer.
            let count = st.alive_count.max(1) as f32;
            let to_nearest = closest.1.normalize_or_zero();
            let dir = if sum.length() > 0.3 * count {
                sum.normalize()
            } else {
                to_nearest
            };
            let bent = (dir + p.tropism)
                .try_normalize()
                .filter(|d| d.dot(to_nearest) > 0.1);
            growth.push((
                tip,
                bent.or(Some(to_nearest)).filter(|d| *d != Vec3::ZERO),
                Some(0.0),
            ));
        }

        // Grow.
        let mut next_trunks = Vec::new();
        let attempted = growth.len();
        for (n, dir, trunk_left) in growth {
            let grown = dir.map(|d| st.nodes[n as usize] + d * p.step);
            match grown {
                // Refused: no direction, or a node already stands there. A refused trunk
                // stops being a trunk; a refused node's pullers are dropped next iteration.
                None => st.refused[n as usize] = iteration,
                Some(q) if st.occupied(q, 0.2 * p.step, p.step) => {
                    st.refused[n as usize] = iteration
                }
                Some(q) => {
                    let child = st.add_node(q, Some(n), p);
                    if let Some(left) = trunk_left
                        && (left > 0.0 || !st.in_range(q, p))
                    {
                        next_trunks.push((child, left));
                    }
                }
            }
        }
        st.trunk_tips = next_trunks;

        if st.dead_since_grid * 4 > st.alive_count.max(1024) {
            st.grid = PointGrid::new(&st.points, &st.alive, p.influence / 3.0);
            let nearest_d2 = &st.nearest_d2;
            st.grid.set_reaches(|i| nearest_d2[i as usize]);
            st.dead_since_grid = 0;
        }

        let finished = st.alive_count == 0 || (st.active.is_empty() && st.trunk_tips.is_empty());
        let stuck = attempted == 0;
        self.growth_seconds += t.elapsed().as_secs_f64();
        if finished || stuck {
            self.done = true;
            return Ok(Step::Done);
        }
        if iteration >= p.max_iterations {
            let msg = format!(
                "{}: warning: space colonization stopped at maxIterations = {} with {} of {} attraction points left (the tree may not reach its envelope: move the root closer or raise influence)",
                self.location,
                p.max_iterations,
                st.alive_count,
                st.points.len()
            );
            self.warnings.push(msg);
            self.done = true;
            return Ok(Step::Done);
        }
        Ok(Step::Continue)
    }

    /// A copy for the preview's scrubber: the state holds no Lua, and a step never reads
    /// `ctx.steps` (a run stopped by `--steps` goes on as the original would).
    fn snapshot(&self) -> Option<Box<dyn Algorithm>> {
        Some(Box::new(self.clone()))
    }

    /// The skeleton with pipe-model radii and orders, as `finish` meshes it.
    fn skeleton(&self) -> Option<Skeleton> {
        let mut skeleton = SpaceColonization::skeleton(self)?;
        let mesh = &self.params.tree.mesh;
        pge_tree::pipe_radii(&mut skeleton, mesh.tip_radius, mesh.exponent);
        pge_tree::assign_orders(&mut skeleton);
        Some(skeleton)
    }

    fn finish(&mut self, ctx: &RunContext) -> Result<Model> {
        let mut skeleton = SpaceColonization::skeleton(self).ok_or_else(|| {
            Error::script(
                self.location.clone(),
                "space colonization finished before init",
            )
        })?;
        let mesh = &self.params.tree.mesh;
        pge_tree::pipe_radii(&mut skeleton, mesh.tip_radius, mesh.exponent);
        pge_tree::assign_orders(&mut skeleton);
        let mut options = self.params.tree.clone();
        options.mesh.radii = pge_tree::RadiiMode::Keep;
        let tree = pge_tree::build_tree(&skeleton, &options, mix(ctx.seed, self.params.seed))
            .map_err(|e| Error::script(self.location.clone(), e.to_string()))?;
        let mut model = Model::new();
        model.stats.warnings.extend(self.warnings.iter().cloned());
        model.stats.add_phase("points", self.points_seconds);
        model.stats.add_phase("growth", self.growth_seconds);
        model.add_model(&tree, glam::Mat4::IDENTITY);
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::algorithm::run;

    fn crown(points: u32) -> Params {
        let mut p = Params::new(Shape::Ellipsoid {
            center: Vec3::new(0.0, 6.0, 0.0),
            radii: Vec3::new(4.0, 3.0, 4.0),
        });
        p.points = Some(points);
        p.step = 0.25;
        p.influence = 2.0;
        p.kill = 0.5;
        p
    }

    fn grow(params: Params, seed: u64) -> (SpaceColonization, Model) {
        let mut sc = SpaceColonization::new(params, Location::new("t.lua", 1)).expect("valid");
        let ctx = RunContext {
            seed,
            ..RunContext::default()
        };
        let model = run(&mut sc, &ctx, &mut |_| {}).expect("grows");
        (sc, model)
    }

    #[test]
    fn a_snapshot_goes_on_as_the_original() {
        let ctx = RunContext::default();
        let mut a = SpaceColonization::new(crown(300), Location::new("t.lua", 1)).expect("valid");
        a.init(&ctx).expect("init");
        for _ in 0..5 {
            a.step(&ctx).expect("step");
        }
        let mut b = a.snapshot().expect("copyable");
        while a.step(&ctx).expect("step") == Step::Continue {}
        while b.step(&ctx).expect("step") == Step::Continue {}
        let (sa, sb) = (
            Algorithm::skeleton(&a).expect("grown"),
            b.skeleton().expect("grown"),
        );
        assert!(sa.positions.len() > 10);
        assert_eq!(sa.positions, sb.positions);
        assert_eq!(sa.parents, sb.parents);
    }

    #[test]
    fn every_point_is_reached_or_out_of_reach() {
        let (sc, model) = grow(crown(2000), 1);
        assert!(sc.warnings().is_empty(), "{:?}", sc.warnings());
        let (pts, alive) = sc.attraction_points().expect("state");
        let skeleton = sc.skeleton().expect("skeleton");
        let influence = sc.params().influence;
        for (p, a) in pts.iter().zip(alive) {
            if *a {
                let nearest = skeleton
                    .positions
                    .iter()
                    .map(|n| n.distance(*p))
                    .fold(f32::INFINITY, f32::min);
                assert!(
                    nearest >= influence,
                    "a live point is within reach of a node ({nearest})"
                );
            }
        }
        let removed = alive.iter().filter(|a| !**a).count();
        assert!(removed > 1900, "only {removed} of 2000 points were reached");
        assert!(model.stats.nodes > 100);
        model.validate().expect("valid model");
    }

    #[test]
    fn the_skeleton_is_one_tree_rooted_at_the_root() {
        let (sc, _) = grow(crown(1500), 3);
        let s = sc.skeleton().expect("skeleton");
        assert_eq!(s.positions[0], Vec3::ZERO);
        assert_eq!(s.parents[0], None);
        for i in 1..s.len() {
            let parent = s.parents[i].expect("only node 0 is a root");
            assert!((parent as usize) < i);
            let len = s.positions[i].distance(s.positions[parent as usize]);
            assert!((len - 0.25).abs() < 1e-4, "segment {i} has length {len}");
        }
        // The trunk reaches the crown: some node lies inside the ellipsoid.
        assert!(s.positions.iter().any(|p| p.y > 4.0));
    }

    #[test]
    fn same_seed_same_tree() {
        let (_, a) = grow(crown(800), 5);
        let (_, b) = grow(crown(800), 5);
        let (_, c) = grow(crown(800), 6);
        assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
        assert_eq!(a.meshes[0].indices, b.meshes[0].indices);
        assert_ne!(a.meshes[0].positions, c.meshes[0].positions);
    }

    #[test]
    fn an_unreachable_crown_stops_at_the_cap_with_a_warning() {
        let mut p = crown(300);
        p.roots = vec![Vec3::new(0.0, -1000.0, 0.0)];
        p.max_iterations = 50;
        let (sc, model) = grow(p, 1);
        assert_eq!(sc.iterations(), 50);
        assert_eq!(sc.warnings().len(), 1);
        assert!(
            sc.warnings()[0].contains("maxIterations = 50"),
            "{}",
            sc.warnings()[0]
        );
        assert_eq!(model.stats.nodes, 51);
    }

    #[test]
    fn a_straight_trunk_grows_first() {
        let mut p = crown(1500);
        p.trunk = 7.0;
        let (sc, model) = grow(p, 2);
        let s = sc.skeleton().expect("skeleton");
        // 28 nodes of 0.25 stand straight above the root, each the parent of the next.
        let mut below = 0u32;
        for k in 1..=28 {
            let above = (0..s.len())
                .find(|&i| {
                    s.parents[i] == Some(below)
                        && s.positions[i].x.abs() < 1e-5
                        && s.positions[i].z.abs() < 1e-5
                })
                .unwrap_or_else(|| panic!("no trunk node {k}"));
            assert!((s.positions[above].y - 0.25 * k as f32).abs() < 1e-4);
            below = above as u32;
        }
        model.validate().expect("valid");
    }

    #[test]
    fn opposite_points_do_not_trap_a_node() {
        // Two points exactly on either side of the root: their pulls cancel.
        let pts = Shape::Union(
            vec![
                Shape::Sphere {
                    center: Vec3::new(-1.0, 0.0, 0.0),
                    radius: 0.01,
                },
                Shape::Sphere {
                    center: Vec3::new(1.0, 0.0, 0.0),
                    radius: 0.01,
                },
            ]
            .into(),
        );
        let mut p = Params::new(pts);
        assert_eq!(p.trunk, 0.0);
        p.points = Some(2);
        p.step = 0.3;
        p.influence = 1.5;
        p.kill = 0.2;
        p.max_iterations = 100;
        let (sc, _) = grow(p, 1);
        assert!(sc.warnings().is_empty(), "it finished on its own");
        assert!(sc.iterations() < 30);
    }

    #[test]
    fn a_start_skeleton_keeps_its_nodes_and_grows_from_its_tips() {
        let mut start = Skeleton::new();
        let r = start.push(Vec3::ZERO, None, 0.3, 0);
        let a = start.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.25, 0);
        start.push(Vec3::new(-1.0, 4.0, 0.0), Some(a), 0.1, 1);
        start.push(Vec3::new(1.0, 4.0, 0.0), Some(a), 0.1, 1);
        let mut p = crown(1500);
        p.start = Some(std::sync::Arc::new(start.clone()));
        let (sc, model) = grow(p, 1);
        model.validate().expect("valid");
        let s = sc.skeleton().expect("skeleton");
        assert_eq!(&s.positions[..4], &start.positions[..]);
        assert_eq!(&s.parents[..4], &start.parents[..]);
        assert_eq!(&s.radii[..4], &start.radii[..]);
        assert!(s.len() > 100, "{}", s.len());
        // Growth hangs on the two tips (or on what grew from them), never on the trunk.
        for i in 4..s.len() {
            let parent = s.parents[i].expect("no new root");
            assert!(parent >= 2, "node {i} grew from the trunk node {parent}");
        }
    }

    /// The growth parameters of `scripts/species/conifer.lua` at its default parameters,
    /// without the options that hold a branch's course: a cone crown, a leader grown first
    /// through it, drooping side branches.
    fn conifer() -> Params {
        let mut p = Params::new(Shape::Cone {
            base: Vec3::new(0.0, 1.5, 0.0),
            apex: Vec3::new(0.0, 12.0, 0.0),
            radius: 3.2,
        });
        p.points = Some(3500);
        p.step = 0.22;
        p.influence = 1.3;
        p.kill = 0.35;
        p.trunk = 12.0 - 1.5 - 0.5;
        p.tropism = Vec3::new(0.0, -0.3, 0.0);
        p
    }

    /// The largest angle in degrees between a segment and the first segment of its
    /// branch: a branch goes on through each node's first-grown child (the apical bud, the
    /// lowest index); later children start side branches.
    fn largest_turn(s: &Skeleton) -> f32 {
        let mut start = vec![Vec3::ZERO; s.len()];
        let mut continued = vec![false; s.len()];
        let mut worst = 0.0f32;
        for i in 0..s.len() {
            let Some(q) = s.parents[i] else { continue };
            let q = q as usize;
            let d = (s.positions[i] - s.positions[q]).normalize();
            start[i] = if continued[q] || start[q] == Vec3::ZERO {
                d
            } else {
                start[q]
            };
            continued[q] = true;
            worst = worst.max(d.dot(start[i]).clamp(-1.0, 1.0).acos().to_degrees());
        }
        worst
    }

    #[test]
    fn conifer_branches_never_turn_back() {
        for seed in [1, 2, 3] {
            // Each tip follows the mean of its pulls alone: the lower branches follow the
            // cone up and back toward the leader, pulled by the points above them.
            let (sc, _) = grow(conifer(), seed);
            let free = largest_turn(&sc.skeleton().expect("skeleton"));
            assert!(free > 140.0, "seed {seed}: the free growth turns {free}");
            let mut p = conifer();
            p.persistence = 0.5;
            p.perception = 90.0;
            p.max_turn = 100.0;
            let (sc, model) = grow(p, seed);
            let turn = largest_turn(&sc.skeleton().expect("skeleton"));
            assert!(turn <= 100.01, "seed {seed}: a branch turns {turn} degrees");
            assert!(sc.warnings().is_empty(), "{:?}", sc.warnings());
            assert!(model.stats.nodes > 1500, "{}", model.stats.nodes);
            model.validate().expect("valid model");
        }
    }

    #[test]
    fn persistence_and_perception_alone_straighten_branches() {
        let (sc, _) = grow(conifer(), 1);
        let free = largest_turn(&sc.skeleton().expect("skeleton"));
        let mut p = conifer();
        p.persistence = 1.0;
        p.perception = 60.0;
        let (sc, _) = grow(p, 1);
        let held = largest_turn(&sc.skeleton().expect("skeleton"));
        assert!(held < free - 20.0, "{free} -> {held}");
    }

    #[test]
    fn bad_parameters_name_themselves() {
        let mut p = crown(10);
        p.kill = 3.0;
        let e = SpaceColonization::new(p, Location::new("t.lua", 4))
            .err()
            .expect("kill > influence");
        assert!(
            e.to_string()
                .starts_with("t.lua:4: kill (3) must be smaller than influence (2)"),
            "{e}"
        );
        let mut p = crown(10);
        p.step = -1.0;
        let e = SpaceColonization::new(p, Location::new("t.lua", 4))
            .err()
            .expect("negative step");
        assert_eq!(e.to_string(), "t.lua:4: step must be a number > 0, got -1");
        for (name, set) in [
            (
                "perception",
                (|p, v| p.perception = v) as fn(&mut Params, f32),
            ),
            ("maxTurn", |p, v| p.max_turn = v),
        ] {
            for bad in [0.0, 181.0, f32::NAN] {
                let mut p = crown(10);
                set(&mut p, bad);
                let e = SpaceColonization::new(p, Location::new("t.lua", 2))
                    .err()
                    .expect("a bad angle");
                assert!(
                    e.to_string()
                        .starts_with(&format!("t.lua:2: {name} must be")),
                    "{e}"
                );
            }
        }
        let mut p = crown(10);
        p.persistence = -1.0;
        assert!(SpaceColonization::new(p, Location::new("t.lua", 4)).is_err());
        let mut p = crown(10);
        p.influence = f32::NAN;
        assert!(SpaceColonization::new(p, Location::new("t.lua", 4)).is_err());
    }
}
