//! The parameters of a colonization and their checks.

use glam::Vec3;
use pge_engine::OptionError;
use pge_engine::geometry::Skeleton;
use pge_tree::TreeOptions;

use crate::points::Mode;
use crate::shape::Shape;

/// The parameters of a colonization (docs/lua-api.md).
#[derive(Clone, Debug)]
pub struct Params {
    /// Where the attraction points are.
    pub envelope: Shape,
    /// How many points (`None`: [`DEFAULT_POINTS`](crate::points::DEFAULT_POINTS), or every vertex in the
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
    pub fn validate(&self) -> Result<(), ParamsError> {
        let positive = |option: &'static str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(OptionError::out_of_range(option, "a number > 0", v))
            }
        };
        positive("step", self.step)?;
        positive("influence", self.influence)?;
        positive("kill", self.kill)?;
        if self.kill >= self.influence {
            return Err(ParamsError::KillNotBelowInfluence {
                kill: self.kill,
                influence: self.influence,
            });
        }
        if !(self.persistence.is_finite() && self.persistence >= 0.0) {
            let p = self.persistence;
            return Err(OptionError::out_of_range("persistence", "a number >= 0", p).into());
        }
        for (option, v) in [("perception", self.perception), ("maxTurn", self.max_turn)] {
            if !(v.is_finite() && v > 0.0 && v <= 180.0) {
                let expected = "an angle in degrees > 0 and <= 180";
                return Err(OptionError::out_of_range(option, expected, v).into());
            }
        }
        if !(self.trunk.is_finite() && self.trunk >= 0.0) {
            return Err(OptionError::out_of_range("trunk", "a number >= 0", self.trunk).into());
        }
        if !self.tropism.is_finite() {
            return Err(OptionError::invalid("tropism", "a finite vector").into());
        }
        if self.roots.is_empty() || self.roots.iter().any(|r| !r.is_finite()) {
            let expected = "a finite vector (roots: a non-empty list of them)";
            return Err(OptionError::invalid("root", expected).into());
        }
        if let Mode::Surround { thickness } = self.mode {
            positive("thickness", thickness)?;
        }
        if self.mode != Mode::Vertices
            && let Some(why) = self.envelope.open_mesh()
        {
            return Err(ParamsError::OpenEnvelope(why));
        }
        if self.max_iterations == 0 {
            return Err(OptionError::out_of_range("maxIterations", "an integer >= 1", 0).into());
        }
        if let Some(start) = &self.start {
            pge_tree::check_skeleton(start).map_err(ParamsError::Start)?;
            if start.is_empty() {
                let expected = "a skeleton with nodes, got an empty one";
                return Err(OptionError::invalid("start", expected).into());
            }
        }
        Ok(())
    }
}

/// Why colonization parameters are refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParamsError {
    /// An option is outside its range.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// The kill distance is not below the influence radius.
    #[error(
        "kill ({kill}) must be smaller than influence ({influence}): points would be removed before they attract"
    )]
    KillNotBelowInfluence {
        /// The kill distance.
        kill: f32,
        /// The influence radius.
        influence: f32,
    },
    /// The envelope holds a mesh that is not closed, and the mode tests for the inside.
    #[error("envelope: {0}; the inside test needs a closed mesh (or use mode = \"vertices\")")]
    OpenEnvelope(String),
    /// The skeleton to grow from is invalid.
    #[error("start: {0}")]
    Start(pge_tree::TreeError),
}
