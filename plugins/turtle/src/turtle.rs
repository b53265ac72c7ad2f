//! The turtle: ABOP's 3D commands, recording branch skeletons (one per colour index).

use glam::{Quat, Vec3};
use pge_engine::geometry::{LeafPoint, Skeleton};

/// How a turtle starts and moves.
#[derive(Clone, Debug, PartialEq)]
pub struct TurtleOptions {
    /// Default angle of turns, pitches and rolls, in degrees (default 90).
    pub angle: f32,
    /// Default length of `F` and `f` (default 1).
    pub step: f32,
    /// Starting width, the branch diameter (default 0.1).
    pub width: f32,
    /// Width multiplier of `!` without parameter (default 0.7).
    pub width_factor: f32,
    /// Tropism vector `T`: after each `F` the heading bends toward it (ABOP §2.3).
    pub tropism: Option<Vec3>,
    /// Susceptibility `e` to tropism: the heading turns by `e * |H x T|` radians (default 0.2).
    pub elasticity: f32,
    /// Default leaf size of `~` without parameter (default 0.25).
    pub leaf_size: f32,
}

impl Default for TurtleOptions {
    fn default() -> Self {
        TurtleOptions {
            angle: 90.0,
            step: 1.0,
            width: 0.1,
            width_factor: 0.7,
            tropism: None,
            elasticity: 0.2,
            leaf_size: 0.25,
        }
    }
}

/// The turtle's state: position, frame `H L U` (heading, left, up; `H x L = U`), width,
/// colour, branch order and the skeleton node it stands on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    /// Position.
    pub position: Vec3,
    /// Heading `H` (unit).
    pub heading: Vec3,
    /// Left `L` (unit).
    pub left: Vec3,
    /// Up `U` (unit).
    pub up: Vec3,
    /// Current width (diameter).
    pub width: f32,
    /// Colour index.
    pub color: u32,
    /// Branch order: +1 inside each `[`.
    pub order: u32,
    /// The node of the current colour's skeleton the turtle stands on, if any.
    node: Option<u32>,
}

/// A mistake in the command stream.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TurtleError {
    /// `]` without a matching `[`.
    #[error("']' (pop) without a matching '[' (push)")]
    PopWithoutPush,
    /// A parameter that is not a finite number.
    #[error("{command}: the parameter must be a finite number, got {value}")]
    NotFinite {
        /// The command.
        command: &'static str,
        /// The value.
        value: f64,
    },
    /// A negative width or leaf size.
    #[error("{command}: the parameter must not be negative, got {value}")]
    Negative {
        /// The command.
        command: &'static str,
        /// The value.
        value: f64,
    },
}

/// A 3D turtle. It starts at the origin heading up `+Y`, with `L = -X` and `U = +Z`, and
/// records what it draws as branch skeletons, one per colour index.
///
/// ```
/// use pge_turtle::{Turtle, TurtleOptions};
/// let mut t = Turtle::new(TurtleOptions::default());
/// t.forward(None).unwrap();
/// t.turn(None).unwrap(); // 90 degrees to the left
/// t.forward(Some(2.0)).unwrap();
/// assert!((t.state().position - glam::Vec3::new(-2.0, 1.0, 0.0)).length() < 1e-6);
/// assert_eq!(t.skeletons()[0].1.len(), 3);
/// ```
#[derive(Clone, Debug)]
pub struct Turtle {
    options: TurtleOptions,
    state: State,
    stack: Vec<State>,
    skeletons: Vec<(u32, Skeleton)>,
}

fn finite(command: &'static str, v: Option<f64>) -> Result<Option<f32>, TurtleError> {
    match v {
        Some(x) if !x.is_finite() => Err(TurtleError::NotFinite { command, value: x }),
        Some(x) => Ok(Some(x as f32)),
        None => Ok(None),
    }
}

impl Turtle {
    /// A turtle at the start.
    #[must_use]
    pub fn new(options: TurtleOptions) -> Turtle {
        let state = Turtle::start(&options);
        Turtle {
            options,
            state,
            stack: Vec::new(),
            skeletons: Vec::new(),
        }
    }

    fn start(options: &TurtleOptions) -> State {
        State {
            position: Vec3::ZERO,
            heading: Vec3::Y,
            left: Vec3::NEG_X,
            up: Vec3::Z,
            width: options.width,
            color: 0,
            order: 0,
            node: None,
        }
    }

    /// Back to the start, forgetting everything drawn.
    pub fn reset(&mut self) {
        self.state = Turtle::start(&self.options);
        self.stack.clear();
        self.skeletons.clear();
    }

    /// The options.
    #[must_use]
    pub fn options(&self) -> &TurtleOptions {
        &self.options
    }

    /// The current state.
    #[must_use]
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The skeletons drawn so far, with their colour index, in order of first use.
    #[must_use]
    pub fn skeletons(&self) -> &[(u32, Skeleton)] {
        &self.skeletons
    }

    fn skeleton_mut(&mut self, color: u32) -> &mut Skeleton {
        let at = match self.skeletons.iter().position(|(c, _)| *c == color) {
            Some(i) => i,
            None => {
                self.skeletons.push((color, Skeleton::new()));
                self.skeletons.len() - 1
            }
        };
        &mut self.skeletons[at].1
    }

    /// The node under the turtle, created as a root if it stands on none.
    fn current_node(&mut self) -> u32 {
        if let Some(n) = self.state.node {
            return n;
        }
        let (pos, radius, order, color) = (
            self.state.position,
            self.state.width * 0.5,
            self.state.order,
            self.state.color,
        );
        let n = self.skeleton_mut(color).push(pos, None, radius, order);
        self.state.node = Some(n);
        n
    }

    /// `F(l)`: moves forward drawing a branch segment (length `step` without parameter).
    pub fn forward(&mut self, length: Option<f64>) -> Result<(), TurtleError> {
        let l = finite("F", length)?.unwrap_or(self.options.step);
        let parent = self.current_node();
        self.state.position += self.state.heading * l;
        let (pos, radius, order, color) = (
            self.state.position,
            self.state.width * 0.5,
            self.state.order,
            self.state.color,
        );
        let n = self
            .skeleton_mut(color)
            .push(pos, Some(parent), radius, order);
        self.state.node = Some(n);
        self.apply_tropism();
        Ok(())
    }

    /// `f(l)`: moves forward without drawing; the next segment starts a new branch.
    pub fn move_forward(&mut self, length: Option<f64>) -> Result<(), TurtleError> {
        let l = finite("f", length)?.unwrap_or(self.options.step);
        self.state.position += self.state.heading * l;
        self.state.node = None;
        Ok(())
    }

    fn apply_tropism(&mut self) {
        let Some(t) = self.options.tropism else {
            return;
        };
        let axis = self.state.heading.cross(t);
        let len = axis.length();
        if len < 1e-9 {
            return;
        }
        let q = Quat::from_axis_angle(axis / len, self.options.elasticity * len);
        self.rotate(q);
    }

    fn rotate(&mut self, q: Quat) {
        let s = &mut self.state;
        s.heading = (q * s.heading).normalize();
        s.left = (q * s.left).normalize();
        s.up = s.heading.cross(s.left).normalize();
        s.left = s.up.cross(s.heading).normalize();
    }

    fn angle(&self, command: &'static str, a: Option<f64>) -> Result<f32, TurtleError> {
        Ok(finite(command, a)?
            .unwrap_or(self.options.angle)
            .to_radians())
    }

    /// `+(a)`: turns left about `U` (negative: right).
    pub fn turn(&mut self, degrees: Option<f64>) -> Result<(), TurtleError> {
        let a = self.angle("+", degrees)?;
        self.rotate(Quat::from_axis_angle(self.state.up, a));
        Ok(())
    }

    /// `&(a)`: pitches down about `L` (negative: up, as `^`).
    pub fn pitch(&mut self, degrees: Option<f64>) -> Result<(), TurtleError> {
        let a = self.angle("&", degrees)?;
        self.rotate(Quat::from_axis_angle(self.state.left, a));
        Ok(())
    }

    /// `\(a)`: rolls left about `H` (negative: right, as `/`).
    pub fn roll(&mut self, degrees: Option<f64>) -> Result<(), TurtleError> {
        let a = self.angle("\\", degrees)?;
        self.rotate(Quat::from_axis_angle(self.state.heading, a));
        Ok(())
    }

    /// The default angle in degrees, negated: `-`, `^` and `/` without parameter.
    #[must_use]
    pub fn negative_angle(&self) -> f64 {
        -f64::from(self.options.angle)
    }

    /// `|`: turns around.
    pub fn turn_around(&mut self) {
        self.rotate(Quat::from_axis_angle(self.state.up, std::f32::consts::PI));
    }

    /// `[`: saves the state; what follows is a branch (its order is one more).
    pub fn push(&mut self) {
        self.stack.push(self.state);
        self.state.order += 1;
    }

    /// `]`: returns to the state saved by the matching `[`.
    pub fn pop(&mut self) -> Result<(), TurtleError> {
        self.state = self.stack.pop().ok_or(TurtleError::PopWithoutPush)?;
        Ok(())
    }

    /// `!(w)`: sets the width; without parameter multiplies it by the width factor.
    pub fn set_width(&mut self, width: Option<f64>) -> Result<(), TurtleError> {
        match finite("!", width)? {
            Some(w) if w < 0.0 => Err(TurtleError::Negative {
                command: "!",
                value: f64::from(w),
            }),
            Some(w) => {
                self.state.width = w;
                Ok(())
            }
            None => {
                self.state.width *= self.options.width_factor;
                Ok(())
            }
        }
    }

    /// `'(i)`: sets the colour index; without parameter adds one. Segments of another colour
    /// go to another skeleton (meshed with that colour).
    pub fn set_color(&mut self, index: Option<f64>) -> Result<(), TurtleError> {
        let c = match finite("'", index)? {
            Some(i) if i < 0.0 => {
                return Err(TurtleError::Negative {
                    command: "'",
                    value: f64::from(i),
                });
            }
            Some(i) => i.round() as u32,
            None => self.state.color + 1,
        };
        if c != self.state.color {
            self.state.color = c;
            self.state.node = None;
        }
        Ok(())
    }

    /// `$`: rolls about `H` so that `L` is horizontal (ABOP: `L = V x H / |V x H|`).
    pub fn roll_to_horizontal(&mut self) {
        let s = &mut self.state;
        let l = Vec3::Y.cross(s.heading);
        if l.length() < 1e-6 {
            return;
        }
        s.left = l.normalize();
        s.up = s.heading.cross(s.left).normalize();
    }

    /// `~(s)`: a leaf of size `s` hung where the turtle stands, pointing along its heading.
    pub fn leaf(&mut self, size: Option<f64>) -> Result<(), TurtleError> {
        let size = match finite("~", size)? {
            Some(s) if s < 0.0 => {
                return Err(TurtleError::Negative {
                    command: "~",
                    value: f64::from(s),
                });
            }
            Some(s) => s,
            None => self.options.leaf_size,
        };
        let node = self.current_node();
        let leaf = LeafPoint {
            node,
            position: self.state.position,
            direction: self.state.heading,
            side: self.state.left,
            size,
        };
        let color = self.state.color;
        self.skeleton_mut(color).leaves.push(leaf);
        Ok(())
    }

    /// Interprets one module by name with its numeric parameters; returns false for a name
    /// that is not a turtle command (so the caller may skip it).
    pub fn command(&mut self, name: &str, params: &[f64]) -> Result<bool, TurtleError> {
        let p = params.first().copied();
        match name {
            "F" => self.forward(p)?,
            "f" => self.move_forward(p)?,
            "+" => self.turn(p)?,
            "-" => self.turn(Some(p.map_or(self.negative_angle(), |a| -a)))?,
            "&" => self.pitch(p)?,
            "^" => self.pitch(Some(p.map_or(self.negative_angle(), |a| -a)))?,
            "\\" => self.roll(p)?,
            "/" => self.roll(Some(p.map_or(self.negative_angle(), |a| -a)))?,
            "|" => self.turn_around(),
            "[" => self.push(),
            "]" => self.pop()?,
            "!" => self.set_width(p)?,
            "'" => self.set_color(p)?,
            "$" => self.roll_to_horizontal(),
            "~" => self.leaf(p)?,
            _ => return Ok(false),
        }
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::assert_approx_eq;

    fn run(t: &mut Turtle, commands: &str) {
        for c in commands.chars() {
            assert!(
                t.command(&c.to_string(), &[]).expect("valid"),
                "{c} is a command"
            );
        }
    }

    #[test]
    fn square_closes_and_records_one_chain() {
        let mut t = Turtle::new(TurtleOptions::default());
        run(&mut t, "F+F+F+F");
        assert_approx_eq!(t.state().position, Vec3::ZERO);
        assert_approx_eq!(t.state().heading, Vec3::X);
        let s = &t.skeletons()[0].1;
        assert_eq!(s.len(), 5);
        assert_eq!(s.parents, vec![None, Some(0), Some(1), Some(2), Some(3)]);
        assert_approx_eq!(s.positions[2], Vec3::new(-1.0, 1.0, 0.0));
        assert_eq!(s.radii[0], 0.05);
    }

    #[test]
    fn branches_return_and_raise_the_order() {
        let mut t = Turtle::new(TurtleOptions::default());
        run(&mut t, "F[+F]F");
        let s = &t.skeletons()[0].1;
        assert_eq!(s.parents, vec![None, Some(0), Some(1), Some(1)]);
        assert_eq!(s.orders, vec![0, 0, 1, 0]);
        assert_approx_eq!(s.positions[3], Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(t.command("]", &[]), Err(TurtleError::PopWithoutPush));
    }

    #[test]
    fn pitch_roll_and_turn_keep_a_right_handed_frame() {
        let mut t = Turtle::new(TurtleOptions {
            angle: 30.0,
            ..TurtleOptions::default()
        });
        run(&mut t, "&&/+^\\|-&");
        let s = t.state();
        assert_approx_eq!(s.heading.cross(s.left), s.up);
        assert!((s.heading.length() - 1.0).abs() < 1e-5);
        let mut t = Turtle::new(TurtleOptions::default());
        t.pitch(Some(90.0)).expect("ok");
        assert_approx_eq!(t.state().heading, Vec3::NEG_Z);
        t.roll(Some(90.0)).expect("ok");
        t.roll_to_horizontal();
        assert!(t.state().left.y.abs() < 1e-6);
    }

    #[test]
    fn tropism_bends_toward_its_vector() {
        let opts = TurtleOptions {
            tropism: Some(Vec3::new(0.0, -1.0, 0.0)),
            elasticity: 0.5,
            ..TurtleOptions::default()
        };
        let mut t = Turtle::new(opts);
        t.turn(Some(90.0)).expect("ok");
        let before = t.state().heading.y;
        t.forward(None).expect("ok");
        assert!(t.state().heading.y < before - 0.1);
    }

    #[test]
    fn widths_colours_and_leaves() {
        let mut t = Turtle::new(TurtleOptions::default());
        t.command("!", &[0.4]).expect("ok");
        t.command("F", &[]).expect("ok");
        t.command("!", &[]).expect("ok");
        t.command("F", &[]).expect("ok");
        t.command("~", &[0.5]).expect("ok");
        t.command("'", &[]).expect("ok");
        t.command("F", &[]).expect("ok");
        let (c0, s0) = &t.skeletons()[0];
        assert_eq!(*c0, 0);
        assert!((s0.radii[2] - 0.14).abs() < 1e-6);
        assert_eq!(s0.leaves.len(), 1);
        assert_eq!(s0.leaves[0].node, 2);
        assert_eq!(s0.leaves[0].size, 0.5);
        let (c1, s1) = &t.skeletons()[1];
        assert_eq!(*c1, 1);
        assert_eq!(s1.parents, vec![None, Some(0)]);
        assert!(matches!(
            t.command("!", &[f64::NAN]),
            Err(TurtleError::NotFinite { .. })
        ));
        assert!(matches!(
            t.command("~", &[-1.0]),
            Err(TurtleError::Negative { .. })
        ));
        assert_eq!(t.command("X", &[]), Ok(false));
        t.reset();
        assert!(t.skeletons().is_empty());
    }
}
