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
//! their nearest node (or within the kill distance). The [`PointGrid`](crate::PointGrid)
//! (cells of a third of the influence radius, split again where points are dense; of two
//! thirds of the influence radius where points are sparse) keeps the largest reach
//! of each cell and sub-cell, and a new node skips, unread, every cell whose distance
//! exceeds that bound. Dead points leave the grid at once (swap-remove in their sub-cell's
//! compact run), so no query reads them again. Points are numbered in the order of the grid
//! of a third of the influence radius, so the points a query reads lie together in memory.
//! An iteration then costs O(attracted points, plus the points each new node changes, plus
//! the cells around it), not points x nodes nor new nodes x points in reach.
//!
//! Each node's pull is summed over its points in increasing point number (the grid's
//! order), a fixed order whatever order the points came within reach in.
//!
//! The known failure of the method, a node pulled by points on opposite sides (its sum of
//! directions cancels) or one that keeps regrowing where a node already stands, is guarded:
//! a cancelled sum grows toward the closest attracting point instead, and a growth that
//! would land within a fifth of a step of an existing node is refused and the points pulling
//! that node are dropped as unreachable. Every iteration therefore adds a node or removes a
//! point, and the iteration cap bounds the rest (with a warning).

use pge_engine::math;
mod ahead;
mod params;
mod state;
#[cfg(test)]
mod tests;

use pge_engine::clock::Instant;

use glam::Vec3;
use pge_engine::geometry::{Model, Skeleton};
use pge_engine::random::mix_seed;
use pge_engine::{Algorithm, Error, Location, Result, RunContext, Step};

pub use params::{Params, ParamsError};
use state::{Pull, State};

use crate::points;

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
    /// The tree's mesh memory, made resident on the pool while the tree grows.
    memory: pge_tree::MeshMemory,
    /// The growth's per-node arrays, made resident by the same job first.
    node_memory: ahead::NodeMemory,
}

impl SpaceColonization {
    /// A colonization with checked parameters; `location` is where script errors point
    /// (the constructor call).
    pub fn new(params: Params, location: Location) -> Result<SpaceColonization> {
        params
            .validate()
            .map_err(|e| Error::script(location.clone(), e.to_string()))?;
        Ok(SpaceColonization {
            params,
            location,
            state: None,
            done: false,
            points_seconds: 0.0,
            growth_seconds: 0.0,
            warnings: Vec::new(),
            memory: pge_tree::MeshMemory::none(),
            node_memory: ahead::NodeMemory::default(),
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
        // Nodes are appended after their parents, the skeleton's order: its arrays are
        // copies of the state's.
        let n = st.nodes.len();
        let mut s = Skeleton {
            positions: st.nodes.clone(),
            parents: st.parents.clone(),
            radii: vec![0.0; n],
            orders: vec![0; n],
            leaves: Vec::new(),
        };
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

impl Algorithm for SpaceColonization {
    fn name(&self) -> &str {
        "space colonization"
    }

    fn init(&mut self, ctx: &RunContext) -> Result<()> {
        let t = Instant::now();
        let p = &self.params;
        // The tree's mesh memory made ahead while it grows: a crown's merged skeleton has
        // at most about two nodes for three points.
        let nodes = p.points.unwrap_or(points::DEFAULT_POINTS) as usize * 2 / 3;
        let sizes = pge_tree::MeshSizes::of_nodes(nodes, &p.tree);
        self.node_memory = ahead::NodeMemory::default();
        let first = self.node_memory.job(nodes);
        self.memory = pge_tree::MeshMemory::prepare_after(sizes, first);
        let pts = points::generate(
            &p.envelope,
            p.mode,
            p.points,
            mix_seed(ctx.seed, self.params.seed) ^ 0x5ace_c010,
            ctx,
            &self.location,
        )?;
        let mut st = State::new(pts, p.influence);
        if let Some(start) = &p.start {
            st.seed_from(start, p);
        } else {
            for root in &p.roots {
                let r = st.add_node(*root, None, p);
                st.flush(p);
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
        self.node_memory.adopt(st);
        st.iteration += 1;
        let iteration = st.iteration;

        // Pulls: each live point adds its unit direction to its nearest node (a tip only
        // perceives the points within its angle of perception).
        let perceive = (p.perception < 180.0).then(|| math::cos(p.perception.to_radians()));
        st.pull(iteration, perceive);

        // Growth directions, all from the state before this iteration's new nodes.
        st.touched.sort_unstable();
        let max_turn = (p.max_turn < 180.0).then(|| math::sin_cos(p.max_turn.to_radians()));
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
                st.pulls[n] = Pull::NONE;
                continue;
            }
            let pull = std::mem::replace(&mut st.pulls[n], Pull::NONE);
            let dir = if pull.sum.length() > 0.1 {
                pull.sum.normalize()
            } else {
                (st.points[pull.closest as usize] - st.nodes[n]).normalize_or_zero()
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
                    if let Some(left) = trunk_left {
                        st.flush(p);
                        if left > 0.0 || !st.in_range(q, p) {
                            next_trunks.push((child, left));
                        }
                    }
                }
            }
        }
        st.flush(p);
        st.trunk_tips = next_trunks;

        let finished = st.alive_count == 0 || (st.none_active() && st.trunk_tips.is_empty());
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
        let seed = mix_seed(ctx.seed, self.params.seed);
        let tree = pge_tree::build_tree_in(&skeleton, &options, seed, &self.memory)
            .map_err(|e| e.into_engine(self.location.clone(), ""))?;
        let mut model = Model::new();
        model.stats.warnings.extend(self.warnings.iter().cloned());
        model.stats.add_phase("points", self.points_seconds);
        model.stats.add_phase("growth", self.growth_seconds);
        model.add_model(&tree, glam::Mat4::IDENTITY);
        Ok(model)
    }
}
