//! The parameters of a conifer (`pge.Conifer{...}`): plain Rust values, their defaults and
//! their ranges.

use glam::Vec3;
use pge_engine::math;
use pge_tree::{MeshOptions, RadiiMode, TreeOptions};

/// The most years (whorls, steps) a conifer grows: `years` and `--steps` above it are errors.
pub const MAX_YEARS: u32 = 1000;

/// The most first-order branches in one whorl.
pub const MAX_PER_WHORL: u32 = 12;

/// The most branches between two whorls.
pub const MAX_INTERWHORL: u32 = 8;

/// The most segments of one branch or shoot: a longer one gets longer segments.
pub const MAX_SEGMENTS: u32 = 64;

/// The most entries of a crown profile list.
pub const MAX_PROFILE: usize = 64;

/// The default node cap (`maxNodes`).
pub const DEFAULT_MAX_NODES: usize = 2_000_000;

/// The largest node cap a script may ask for.
pub const MAX_NODES: usize = 50_000_000;

/// How the length of first-order branches falls from the crown's base to its apex: the
/// relative length at `t`, the depth below the apex as a fraction of the crown's depth
/// (0 at the apex, 1 at the crown base).
#[derive(Clone, Debug, PartialEq)]
pub enum Crown {
    /// A cone: length grows linearly with `t` (spruce, fir; Lua `"conic"`).
    Conic,
    /// A rounded top: `sin(t * pi / 2)` (pine, cedar; Lua `"ogive"`).
    Ogive,
    /// A narrow column: `min(1, 3 t)` (cypress, columnar forms; Lua `"columnar"`).
    Columnar,
    /// Relative lengths at evenly spaced depths from the apex (first) to the crown base
    /// (last), linearly interpolated (Lua: a list of numbers).
    Profile(Vec<f32>),
}

impl Crown {
    /// The Lua names of the built-in shapes.
    pub const NAMES: [&'static str; 3] = ["conic", "ogive", "columnar"];

    /// The shape of a Lua name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Crown> {
        match name {
            "conic" => Some(Crown::Conic),
            "ogive" => Some(Crown::Ogive),
            "columnar" => Some(Crown::Columnar),
            _ => None,
        }
    }

    /// The relative branch length at depth `t` (clamped to `[0, 1]`).
    #[must_use]
    pub fn length_at(&self, t: f32) -> f32 {
        let t = t.clamp(0.0, 1.0);
        match self {
            Crown::Conic => t,
            Crown::Ogive => math::sin(t * std::f32::consts::FRAC_PI_2),
            Crown::Columnar => (3.0 * t).min(1.0),
            Crown::Profile(values) => match values.len() {
                0 => 0.0,
                1 => values[0],
                n => {
                    let x = t * (n - 1) as f32;
                    let k = (x.floor() as usize).min(n - 2);
                    let f = x - k as f32;
                    values[k] + (values[k + 1] - values[k]) * f
                }
            },
        }
    }
}

/// How second- and third-order shoots sit along their parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SprayPattern {
    /// One shoot per node, left and right in turn (Lua `"alternate"`).
    #[default]
    Alternate,
    /// Two shoots per node, one on each side (Lua `"paired"`).
    Paired,
}

impl SprayPattern {
    /// The Lua names, in the order of the variants.
    pub const NAMES: [&'static str; 2] = ["alternate", "paired"];
}

/// The parameters of an excurrent tree (`pge.Conifer{...}`); see docs/lua-api.md
/// for the meaning of each.
#[derive(Clone, Debug, PartialEq)]
pub struct ConiferParams {
    /// Years grown when `--steps` does not say; each year adds one internode and one whorl
    /// (default 20).
    pub years: u32,
    /// Height reached after `years` years, metres (default 12): the internode is
    /// `height / years`.
    pub height: f32,
    /// Length of the longest first-order branch after `years` years, metres (default 3).
    pub crown_radius: f32,
    /// How branch lengths fall toward the apex (default conic).
    pub crown: Crown,
    /// Fraction of the height below which the branches have been shed (default 0.1).
    pub crown_base: f32,
    /// First-order branches per whorl, drawn in `(min, max)` (default (4, 6)).
    pub per_whorl: (u32, u32),
    /// Degrees each whorl is turned from the one below (default 137.5).
    pub twist: f32,
    /// Angle between a branch and the trunk above it, degrees, at the apex and at the crown
    /// base (default (60, 95)).
    pub angle: (f32, f32),
    /// Degrees the tip of the longest branch bends down under its weight (default 20).
    pub droop: f32,
    /// Random variation of azimuths, angles and lengths, 0..=1 (default 0.15).
    pub jitter: f32,
    /// Sideways wander of the leader's whorl nodes, as a fraction of the internode
    /// (default 0.02).
    pub waviness: f32,
    /// Segment length of branches and shoots, metres; shoots grow at the nodes (default 0.25).
    pub segment: f32,
    /// Branch orders: 1 (no sprays), 2 (sprays) or 3 (sprays of sprays) (default 2).
    pub orders: u32,
    /// Angle between a shoot and its parent, degrees (default 55).
    pub spray_angle: f32,
    /// Shoot length as a fraction of the parent's length beyond the shoot (default 0.5).
    pub spray_length: f32,
    /// Degrees the tip of a shoot bends down (default 10).
    pub spray_droop: f32,
    /// One shoot per node or two (default alternate).
    pub spray_pattern: SprayPattern,
    /// Fraction of each branch, from the trunk out, without shoots (default 0.1).
    pub bare: f32,
    /// Small branches between two whorls, drawn in `(min, max)` (default (0, 0)).
    pub interwhorl: (u32, u32),
    /// Largest ratio of a first-order branch's radius to the trunk's where it joins
    /// (default 0.45): thicker branches are thinned, their whole subtree alike.
    pub joint_ratio: f32,
    /// The base of the trunk.
    pub root: Vec3,
    /// Mixed into the run's seed, so one script can grow several different trees.
    pub seed: u64,
    /// The node cap: a skeleton that would grow past it is an error.
    pub max_nodes: usize,
    /// Bark and leaf options; radii are the generator's own (pipe model, joints clamped)
    /// unless `mesh.radii` asks for the mesher's pipe model.
    pub tree: TreeOptions,
}

impl Default for ConiferParams {
    fn default() -> Self {
        ConiferParams {
            years: 20,
            height: 12.0,
            crown_radius: 3.0,
            crown: Crown::Conic,
            crown_base: 0.1,
            per_whorl: (4, 6),
            twist: 137.5,
            angle: (60.0, 95.0),
            droop: 20.0,
            jitter: 0.15,
            waviness: 0.02,
            segment: 0.25,
            orders: 2,
            spray_angle: 55.0,
            spray_length: 0.5,
            spray_droop: 10.0,
            spray_pattern: SprayPattern::Alternate,
            bare: 0.1,
            interwhorl: (0, 0),
            joint_ratio: 0.45,
            root: Vec3::ZERO,
            seed: 0,
            max_nodes: DEFAULT_MAX_NODES,
            tree: TreeOptions {
                mesh: MeshOptions {
                    radii: RadiiMode::Keep,
                    ..MeshOptions::default()
                },
                leaves: None,
                lod: None,
            },
        }
    }
}

/// A parameter out of its range: what [`ConiferParams::validate`] refuses, naming the option
/// as Lua spells it and what it needs.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// A number that must be finite and above 0.
    #[error("{name} must be a number > 0, got {value}")]
    NotPositive {
        /// The option.
        name: &'static str,
        /// What it was.
        value: f32,
    },
    /// A number that must lie in `lo..=hi`.
    #[error("{name} must be a number between {lo} and {hi}, got {value}")]
    Between {
        /// The option.
        name: &'static str,
        /// What it was.
        value: f32,
        /// The least allowed.
        lo: f32,
        /// The most allowed.
        hi: f32,
    },
    /// An integer that must lie in `min..=max`.
    #[error("{name} must be an integer between {min} and {max}, got {value}")]
    Integer {
        /// The option.
        name: &'static str,
        /// What it was.
        value: u64,
        /// The least allowed.
        min: u64,
        /// The most allowed.
        max: u64,
    },
    /// A `{min, max}` count range that must satisfy `least <= min <= max <= most`.
    #[error(
        "{name} must be {{min, max}} with {least} <= min <= max <= {most}, got {{{}, {}}}",
        got.0,
        got.1
    )]
    CountRange {
        /// The option.
        name: &'static str,
        /// What it was.
        got: (u32, u32),
        /// The least allowed `min`.
        least: u32,
        /// The most allowed `max`.
        most: u32,
    },
    /// A crown profile of too few or too many values.
    #[error("crown must be a list of 2 to {MAX_PROFILE} numbers, got {0}")]
    ProfileLength(usize),
    /// A crown profile value that is negative or not a number.
    #[error("crown values must be numbers >= 0, got {0}")]
    ProfileValue(f32),
    /// `jointRatio` outside `(0, 1]`.
    #[error("jointRatio must be a number greater than 0 and at most 1, got {0}")]
    JointRatio(f32),
    /// A root position that is not finite.
    #[error("root must be a finite vector")]
    Root,
}

fn positive(name: &'static str, value: f32) -> Result<(), ParamError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ParamError::NotPositive { name, value })
    }
}

fn between(name: &'static str, value: f32, lo: f32, hi: f32) -> Result<(), ParamError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(())
    } else {
        Err(ParamError::Between {
            name,
            value,
            lo,
            hi,
        })
    }
}

fn integer(name: &'static str, value: u64, min: u64, max: u64) -> Result<(), ParamError> {
    if (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(ParamError::Integer {
            name,
            value,
            min,
            max,
        })
    }
}

fn count_range(
    name: &'static str,
    got: (u32, u32),
    least: u32,
    most: u32,
) -> Result<(), ParamError> {
    let (lo, hi) = got;
    if lo < least || hi > most || lo > hi {
        return Err(ParamError::CountRange {
            name,
            got,
            least,
            most,
        });
    }
    Ok(())
}

impl ConiferParams {
    /// Checks every range: the error names the option (as Lua spells it) and what it needs.
    pub fn validate(&self) -> Result<(), ParamError> {
        integer("years", self.years.into(), 1, MAX_YEARS.into())?;
        positive("height", self.height)?;
        positive("crownRadius", self.crown_radius)?;
        if let Crown::Profile(values) = &self.crown {
            if values.len() < 2 || values.len() > MAX_PROFILE {
                return Err(ParamError::ProfileLength(values.len()));
            }
            if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(ParamError::ProfileValue(*v));
            }
        }
        between("crownBase", self.crown_base, 0.0, 0.95)?;
        count_range("perWhorl", self.per_whorl, 1, MAX_PER_WHORL)?;
        between("twist", self.twist, -360.0, 360.0)?;
        between("angle (apex)", self.angle.0, 0.0, 180.0)?;
        between("angle (base)", self.angle.1, 0.0, 180.0)?;
        between("droop", self.droop, 0.0, 90.0)?;
        between("jitter", self.jitter, 0.0, 1.0)?;
        between("waviness", self.waviness, 0.0, 0.5)?;
        positive("segment", self.segment)?;
        integer("orders", self.orders.into(), 1, 3)?;
        between("sprayAngle", self.spray_angle, 0.0, 90.0)?;
        between("sprayLength", self.spray_length, 0.0, 2.0)?;
        between("sprayDroop", self.spray_droop, 0.0, 90.0)?;
        between("bare", self.bare, 0.0, 1.0)?;
        count_range("interwhorl", self.interwhorl, 0, MAX_INTERWHORL)?;
        if !(self.joint_ratio.is_finite() && self.joint_ratio > 0.0 && self.joint_ratio <= 1.0) {
            return Err(ParamError::JointRatio(self.joint_ratio));
        }
        if !self.root.is_finite() {
            return Err(ParamError::Root);
        }
        integer("maxNodes", self.max_nodes as u64, 1, MAX_NODES as u64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profiles_interpolate_and_clamp() {
        let p = Crown::Profile(vec![0.0, 1.0, 0.5]);
        assert_eq!(p.length_at(0.0), 0.0);
        assert_eq!(p.length_at(0.25), 0.5);
        assert_eq!(p.length_at(0.5), 1.0);
        assert_eq!(p.length_at(1.0), 0.5);
        assert_eq!(p.length_at(7.0), 0.5);
        assert_eq!(Crown::Conic.length_at(0.3), 0.3);
        assert_eq!(Crown::Columnar.length_at(0.5), 1.0);
        assert!((Crown::Ogive.length_at(1.0) - 1.0).abs() < 1e-6);
        assert!(Crown::Ogive.length_at(0.2) > 0.2);
    }

    #[test]
    fn bad_values_name_their_option() {
        let bad = |f: fn(&mut ConiferParams)| {
            let mut p = ConiferParams::default();
            f(&mut p);
            p.validate().expect_err("invalid").to_string()
        };
        assert_eq!(
            bad(|p| p.years = 0),
            "years must be an integer between 1 and 1000, got 0"
        );
        assert_eq!(
            bad(|p| p.per_whorl = (2, 40)),
            "perWhorl must be {min, max} with 1 <= min <= max <= 12, got {2, 40}"
        );
        assert_eq!(
            bad(|p| p.height = f32::NAN),
            "height must be a number > 0, got NaN"
        );
        assert_eq!(
            bad(|p| p.crown = Crown::Profile(vec![1.0])),
            "crown must be a list of 2 to 64 numbers, got 1"
        );
        assert_eq!(
            bad(|p| p.orders = 4),
            "orders must be an integer between 1 and 3, got 4"
        );
        assert!(bad(|p| p.joint_ratio = 0.0).starts_with("jointRatio"));
        ConiferParams::default()
            .validate()
            .expect("defaults are valid");
    }
}
