//! The transport model as a step-wise [`Algorithm`]: one step is one feeding; `finish`
//! turns the branches into the engine's [`Skeleton`] and meshes it with [`pge_tree`].

use pge_engine::clock::Instant;
use std::sync::Arc;

use glam::{DVec3, Mat4, Vec3};
use pge_engine::geometry::{Model, Skeleton};
use pge_engine::random::mix_seed;
use pge_engine::{Algorithm, Error, Location, OptionError, Result, RunContext, Step};
use pge_tree::{RadiiMode, TreeOptions};

use crate::transport::{NONE, TransportParams, TransportTree};

/// The most feedings a growth takes (`steps`, `--steps`).
pub const MAX_STEPS: u32 = 100_000;

/// The default branch cap: a feeding that would grow the tree past it stops the run.
pub const DEFAULT_MAX_BRANCHES: usize = 1_000_000;

/// The parameters of a growth (`pge.Growth{...}`).
#[derive(Clone, Debug)]
pub struct GrowthParams {
    /// The transport model's parameters (ratio, spread, splitsize, ...).
    pub transport: TransportParams,
    /// Feedings taken when `--steps` does not say (default 60).
    pub steps: u32,
    /// Where the trunk starts (without `start`).
    pub root: Vec3,
    /// The trunk's initial direction (without `start`; default +Y).
    pub direction: Vec3,
    /// A skeleton grown by another method; growth continues from each of its tips, in the
    /// direction of the tip's last segment, each tip receiving an equal share of the feed.
    /// Its nodes are kept as they are, first and in order, in the result.
    pub start: Option<Arc<Skeleton>>,
    /// Lengths and radii of the grown branches are multiplied by this (default 1: the
    /// seed's units, a tree of about 15 after 60 feedings).
    pub scale: f32,
    /// Radii are further multiplied by this (default 0.4): the transport model's areas
    /// give stout, baobab-like limbs, and like the seed's renderer we draw them thinner
    /// than they grow. 1 draws the model's own radii.
    pub girth: f32,
    /// The branch cap (default [`DEFAULT_MAX_BRANCHES`]).
    pub max_branches: usize,
    /// Mixed into the run's seed, so one script can grow several different trees.
    pub seed: u64,
    /// Bark and leaf options; radii are the transport model's own unless `mesh.radii` asks
    /// for the pipe model.
    pub tree: TreeOptions,
}

impl Default for GrowthParams {
    fn default() -> Self {
        GrowthParams {
            transport: TransportParams::default(),
            steps: 60,
            root: Vec3::ZERO,
            direction: Vec3::Y,
            start: None,
            scale: 1.0,
            girth: 0.4,
            max_branches: DEFAULT_MAX_BRANCHES,
            seed: 0,
            tree: TreeOptions {
                mesh: pge_tree::MeshOptions {
                    radii: RadiiMode::Keep,
                    ..pge_tree::MeshOptions::default()
                },
                leaves: None,
                lod: None,
            },
        }
    }
}

impl GrowthParams {
    /// Checks every range: the error names the option and the range it needs.
    pub fn validate(&self) -> Result<(), GrowthError> {
        self.transport.validate()?;
        if self.steps > MAX_STEPS {
            return Err(GrowthError::Steps(self.steps));
        }
        if !self.root.is_finite() {
            return Err(OptionError::invalid("root", "a finite vector").into());
        }
        if !self.direction.is_finite() || self.direction.length_squared() == 0.0 {
            return Err(OptionError::invalid("direction", "a finite, non-zero vector").into());
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(OptionError::out_of_range("scale", "a number > 0", self.scale).into());
        }
        if !(self.girth.is_finite() && self.girth > 0.0) {
            return Err(OptionError::out_of_range("girth", "a number > 0", self.girth).into());
        }
        if self.max_branches < 1 {
            return Err(OptionError::invalid("maxBranches", "an integer >= 1").into());
        }
        if let Some(s) = &self.start {
            pge_tree::check_skeleton(s).map_err(GrowthError::Start)?;
            if s.is_empty() {
                return Err(GrowthError::EmptyStart);
            }
        }
        Ok(())
    }
}

/// Why growth parameters are refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GrowthError {
    /// An option is outside its range.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// More steps than the growth takes.
    #[error("steps must be an integer between 0 and {MAX_STEPS}, got {0}")]
    Steps(u32),
    /// The skeleton to grow from is invalid.
    #[error("start: {0}")]
    Start(pge_tree::TreeError),
    /// The skeleton to grow from has no node.
    #[error("start: the skeleton has no node to grow from")]
    EmptyStart,
}

/// Growth by nutrient transport as an [`Algorithm`].
#[derive(Clone)]
pub struct Growth {
    params: GrowthParams,
    location: Location,
    tree: Option<TransportTree>,
    done: bool,
    seconds: f64,
}

impl Growth {
    /// A growth with checked parameters; `location` is where script errors point.
    pub fn new(params: GrowthParams, location: Location) -> Result<Growth> {
        params
            .validate()
            .map_err(|e| Error::script(location.clone(), e.to_string()))?;
        Ok(Growth {
            params,
            location,
            tree: None,
            done: false,
            seconds: 0.0,
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &GrowthParams {
        &self.params
    }

    /// The transport tree, or `None` before `init`.
    #[must_use]
    pub fn transport(&self) -> Option<&TransportTree> {
        self.tree.as_ref()
    }

    /// The roots of a new tree: the root, or one per tip of the start skeleton.
    fn roots(&self) -> Vec<(DVec3, DVec3, f64)> {
        let Some(start) = &self.params.start else {
            return vec![(
                self.params.root.as_dvec3(),
                self.params.direction.as_dvec3(),
                1.0,
            )];
        };
        let tips = start.tips();
        let share = 1.0 / tips.len() as f64;
        tips.iter()
            .map(|&t| {
                let p = start.positions[t as usize];
                let dir = start.parents[t as usize]
                    .and_then(|q| (p - start.positions[q as usize]).try_normalize())
                    .unwrap_or(self.params.direction);
                (p.as_dvec3(), dir.as_dvec3(), share)
            })
            .collect()
    }

    /// The skeleton of the current state: the start skeleton's nodes first (unchanged but
    /// for radii thickened to carry what grew above them), then the base of a root grown
    /// without `start`, then one node at the end of every branch that has length.
    /// Radii are `sqrt(area / pi)` times `scale * girth`; orders follow the heavier child.
    #[must_use]
    pub fn skeleton(&self) -> Option<Skeleton> {
        let tree = self.tree.as_ref()?;
        let p = &self.params;
        let mut s = match &p.start {
            Some(start) => (**start).clone(),
            None => Skeleton::new(),
        };
        let fixed = s.len();
        let tips = p.start.as_ref().map(|st| st.tips()).unwrap_or_default();
        let ends = tree.ends();
        let scale = f64::from(p.scale);
        let thick = scale * f64::from(p.girth);
        let mut node = vec![NONE; tree.len()];
        let mut base = vec![NONE; tree.len()];
        let mut origin = vec![DVec3::ZERO; tree.len()];
        for (k, &(b, o, _)) in tree.roots.iter().enumerate() {
            origin[b as usize] = o;
            base[b as usize] = match tips.get(k) {
                Some(&tip) => tip,
                None => s.push(o.as_vec3(), None, (tree.radius(b) * thick) as f32, 0),
            };
        }
        let heavy_is_a = tree.params().ratio >= 0.5;
        let mut order = vec![0u32; tree.len()];
        for b in 0..tree.len() {
            let parent = tree.parent[b];
            let (anchor, o) = if parent == NONE {
                let anchor = base[b];
                (anchor, s.orders[anchor as usize])
            } else {
                let pb = parent as usize;
                let is_a = tree.children[pb][0] == b as u32;
                let lateral = u32::from(is_a != heavy_is_a);
                origin[b] = origin[pb];
                (node[pb], order[pb] + lateral)
            };
            order[b] = o;
            if tree.length[b] <= 0.0 || anchor == NONE {
                continue;
            }
            let end = origin[b] + (ends[b] - origin[b]) * scale;
            node[b] = s.push(
                end.as_vec3(),
                Some(anchor),
                (tree.radius(b as u32) * thick) as f32,
                o,
            );
        }
        // The fixed nodes carry what grew above them: r^2 >= the sum of the children's.
        let mut carried = vec![0.0f64; s.len()];
        for i in (0..s.len()).rev() {
            if i < fixed {
                let r = f64::from(s.radii[i]).max(carried[i].sqrt());
                s.radii[i] = r as f32;
            }
            if let Some(q) = s.parents[i] {
                carried[q as usize] += f64::from(s.radii[i]).powi(2);
            }
        }
        Some(s)
    }

    /// Whether the growth has taken all its feedings.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.done
    }
}

impl Algorithm for Growth {
    fn name(&self) -> &str {
        "growth"
    }

    fn init(&mut self, ctx: &RunContext) -> Result<()> {
        let seed = mix_seed(ctx.seed, self.params.seed);
        // MT19937 takes a 32-bit seed: fold the 64 bits.
        let seed32 = (seed ^ (seed >> 32)) as u32;
        self.tree = Some(TransportTree::new(
            self.params.transport,
            &self.roots(),
            seed32,
        ));
        self.done = false;
        self.seconds = 0.0;
        Ok(())
    }

    fn step(&mut self, ctx: &RunContext) -> Result<Step> {
        // No latch on `done`: a state that stopped at `ctx.steps` goes on under a larger one
        // (the scrubber keeps copies of it).
        ctx.check_deadline(&self.location)?;
        let t = Instant::now();
        let limit = ctx.steps.unwrap_or(self.params.steps);
        let Some(tree) = self.tree.as_mut() else {
            return Err(Error::script(
                self.location.clone(),
                "growth stepped before init",
            ));
        };
        if tree.steps() >= limit {
            self.done = true;
            return Ok(Step::Done);
        }
        tree.feed(self.params.max_branches).map_err(|e| {
            Error::script(
                self.location.clone(),
                format!(
                    "pge.Growth: feeding {} would grow the tree to {} branches, past the cap \
                     of {} (maxBranches): lower feed or steps, or raise splitsize",
                    tree.steps() + 1,
                    e.would_have,
                    e.cap
                ),
            )
        })?;
        self.seconds += t.elapsed().as_secs_f64();
        if tree.steps() >= limit {
            self.done = true;
            return Ok(Step::Done);
        }
        Ok(Step::Continue)
    }

    fn finish(&mut self, ctx: &RunContext) -> Result<Model> {
        let skeleton = self
            .skeleton()
            .ok_or_else(|| Error::script(self.location.clone(), "growth finished before init"))?;
        let tree = pge_tree::build_tree(
            &skeleton,
            &self.params.tree,
            mix_seed(ctx.seed, self.params.seed),
        )
        .map_err(|e| e.into_engine(self.location.clone(), ""))?;
        let mut model = Model::new();
        model.stats.add_phase("growth", self.seconds);
        model.add_model(&tree, Mat4::IDENTITY);
        Ok(model)
    }

    fn planned_steps(&self) -> Option<u32> {
        Some(self.params.steps)
    }

    fn skeleton(&self) -> Option<Skeleton> {
        Growth::skeleton(self)
    }

    fn snapshot(&self) -> Option<Box<dyn Algorithm>> {
        Some(Box::new(self.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::algorithm::run;

    fn grow(params: GrowthParams, seed: u64, steps: Option<u32>) -> (Growth, Model) {
        let mut g = Growth::new(params, Location::new("t.lua", 1)).expect("valid");
        let ctx = RunContext {
            seed,
            steps,
            ..RunContext::default()
        };
        let model = run(&mut g, &ctx, &mut |_| {}).expect("grows");
        (g, model)
    }

    #[test]
    fn a_growth_is_a_tree_with_transport_radii() {
        let (g, model) = grow(GrowthParams::default(), 1, None);
        model.validate().expect("valid");
        let s = g.skeleton().expect("skeleton");
        let t = g.transport().expect("tree");
        assert_eq!(t.steps(), 60);
        assert_eq!(s.parents[0], None);
        assert_eq!(s.positions[0], Vec3::ZERO);
        assert!(s.len() > 50, "{}", s.len());
        assert_eq!(model.stats.nodes, s.len() as u64);
        // The trunk's radius is the root branch's sqrt(area / pi), times the girth.
        assert!((f64::from(s.radii[1]) - 0.4 * t.radius(0)).abs() < 1e-6);
        for i in 1..s.len() {
            assert!(s.parents[i].expect("one root") < i as u32);
        }
    }

    #[test]
    fn steps_override_and_determinism() {
        let (a, _) = grow(GrowthParams::default(), 3, Some(25));
        let (b, _) = grow(GrowthParams::default(), 3, Some(25));
        let (c, _) = grow(GrowthParams::default(), 4, Some(25));
        assert_eq!(a.transport().expect("t").steps(), 25);
        assert_eq!(a.skeleton(), b.skeleton());
        assert_ne!(a.skeleton(), c.skeleton());
    }

    #[test]
    fn growth_continues_from_a_start_skeleton_and_keeps_its_nodes() {
        let mut start = Skeleton::new();
        let r = start.push(Vec3::ZERO, None, 0.0, 0);
        let f = start.push(Vec3::new(0.0, 2.0, 0.0), Some(r), 0.0, 0);
        start.push(Vec3::new(-1.0, 3.0, 0.0), Some(f), 0.0, 1);
        start.push(Vec3::new(1.0, 3.0, 0.0), Some(f), 0.0, 1);
        let params = GrowthParams {
            start: Some(Arc::new(start.clone())),
            steps: 20,
            ..GrowthParams::default()
        };
        let (g, model) = grow(params, 1, None);
        model.validate().expect("valid");
        let s = g.skeleton().expect("skeleton");
        assert_eq!(&s.positions[..4], &start.positions[..]);
        assert_eq!(&s.parents[..4], &start.parents[..]);
        assert!(s.len() > 8);
        // Growth hangs on the two tips only, and the fixed nodes carry it.
        for i in 4..s.len() {
            let parent = s.parents[i].expect("no new root");
            assert!(parent >= 2, "node {i} hangs on {parent}");
        }
        assert!(s.radii[0] > 0.0 && s.radii[0] >= s.radii[2]);
    }

    #[test]
    fn the_cap_is_a_clear_error() {
        let params = GrowthParams {
            transport: TransportParams {
                feed: 1e4,
                splitsize: 0.05,
                ..TransportParams::default()
            },
            max_branches: 5000,
            steps: 200,
            ..GrowthParams::default()
        };
        let mut g = Growth::new(params, Location::new("t.lua", 9)).expect("valid");
        let e = run(&mut g, &RunContext::default(), &mut |_| {}).expect_err("explodes");
        let e = e.to_string();
        assert!(e.starts_with("t.lua:9: pge.Growth: feeding "), "{e}");
        assert!(e.contains("past the cap of 5000 (maxBranches)"), "{e}");
    }

    #[test]
    fn bad_parameters_name_themselves() {
        let params = GrowthParams {
            transport: TransportParams {
                ratio: 0.0,
                ..TransportParams::default()
            },
            ..GrowthParams::default()
        };
        let e = Growth::new(params, Location::new("t.lua", 2))
            .err()
            .expect("bad");
        assert_eq!(
            e.to_string(),
            "t.lua:2: ratio must be a number between 0 and 1 (exclusive), got 0"
        );
    }
}
