//! The conifer as a step-wise [`Algorithm`]: one step is one year, which lays down one
//! internode of the leader and one whorl of buds; `finish` builds the skeleton of the tree
//! at its age and meshes it with [`pge_tree`].

use pge_engine::clock::Instant;

use glam::Mat4;
use pge_engine::geometry::{Model, Skeleton};
use pge_engine::{Algorithm, Error, Location, Result, RunContext, Step};

use crate::build::{Built, Whorl, build, mix64};
use crate::params::{ConiferParams, MAX_YEARS};

/// An excurrent tree (a pine, a spruce) as an [`Algorithm`].
#[derive(Clone, Debug)]
pub struct Conifer {
    params: ConiferParams,
    location: Location,
    seed: u64,
    whorls: Vec<Whorl>,
    seconds: f64,
}

/// The run's seed combined with a script's own `seed`, the identity for `seed = 0`.
fn mix(run: u64, own: u64) -> u64 {
    if own == 0 { run } else { run ^ mix64(own) }
}

impl Conifer {
    /// A conifer with checked parameters; `location` is where script errors point.
    pub fn new(params: ConiferParams, location: Location) -> Result<Conifer> {
        params
            .validate()
            .map_err(|e| Error::script(location.clone(), e.to_string()))?;
        Ok(Conifer {
            params,
            location,
            seed: 0,
            whorls: Vec::new(),
            seconds: 0.0,
        })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &ConiferParams {
        &self.params
    }

    /// The years grown so far (whorls laid down).
    #[must_use]
    pub fn age(&self) -> u32 {
        self.whorls.len() as u32
    }

    /// The whorls laid down so far, the lowest first.
    #[must_use]
    pub fn whorls(&self) -> &[Whorl] {
        &self.whorls
    }

    /// The skeleton at the current age and where its branches are; an error when it would
    /// pass the node cap.
    pub fn build(&self) -> Result<Built> {
        build(&self.params, &self.whorls, self.seed).map_err(|e| {
            Error::script(
                self.location.clone(),
                format!(
                    "pge.Conifer: at {} years the tree would have more than {} nodes \
                     (maxNodes): lower years, perWhorl, orders or sprayLength, or raise \
                     segment",
                    self.age(),
                    e.cap
                ),
            )
        })
    }
}

impl Algorithm for Conifer {
    fn name(&self) -> &str {
        "conifer"
    }

    fn init(&mut self, ctx: &RunContext) -> Result<()> {
        self.seed = mix(ctx.seed, self.params.seed);
        self.whorls.clear();
        self.seconds = 0.0;
        Ok(())
    }

    fn step(&mut self, ctx: &RunContext) -> Result<Step> {
        ctx.check_deadline(&self.location)?;
        let limit = ctx.steps.unwrap_or(self.params.years);
        if self.age() >= limit {
            return Ok(Step::Done);
        }
        if self.age() >= MAX_YEARS {
            return Err(Error::script(
                self.location.clone(),
                format!("pge.Conifer: a conifer grows at most {MAX_YEARS} years (steps)"),
            ));
        }
        let t = Instant::now();
        let year = self.age() + 1;
        self.whorls.push(Whorl::draw(&self.params, self.seed, year));
        self.seconds += t.elapsed().as_secs_f64();
        Ok(if self.age() >= limit {
            Step::Done
        } else {
            Step::Continue
        })
    }

    fn finish(&mut self, _ctx: &RunContext) -> Result<Model> {
        let t = Instant::now();
        let built = self.build()?;
        let seconds = self.seconds + t.elapsed().as_secs_f64();
        let tree = pge_tree::build_tree(&built.skeleton, &self.params.tree, self.seed)
            .map_err(|e| e.into_engine(self.location.clone(), ""))?;
        let mut model = Model::new();
        model.stats.add_phase("growth", seconds);
        model.add_model(&tree, Mat4::IDENTITY);
        Ok(model)
    }

    fn planned_steps(&self) -> Option<u32> {
        Some(self.params.years)
    }

    fn skeleton(&self) -> Option<Skeleton> {
        self.build().ok().map(|b| b.skeleton)
    }

    fn snapshot(&self) -> Option<Box<dyn Algorithm>> {
        Some(Box::new(self.clone()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::algorithm::run;

    fn grow(params: ConiferParams, seed: u64, steps: Option<u32>) -> (Conifer, Model) {
        let mut c = Conifer::new(params, Location::new("t.lua", 1)).expect("valid");
        let ctx = RunContext {
            seed,
            steps,
            ..RunContext::default()
        };
        let model = run(&mut c, &ctx, &mut |_| {}).expect("grows");
        (c, model)
    }

    #[test]
    fn a_conifer_is_a_valid_tree_with_a_step_per_year() {
        let (c, model) = grow(ConiferParams::default(), 1, None);
        model.validate().expect("valid");
        assert_eq!(c.age(), 20);
        let s = c.skeleton().expect("skeleton");
        assert!(s.len() > 500, "{}", s.len());
        assert!(model.stats.nodes > 0);
        let (young, _) = grow(ConiferParams::default(), 1, Some(8));
        assert_eq!(young.age(), 8);
        assert!(young.skeleton().expect("young").len() < s.len());
    }

    #[test]
    fn the_same_seed_grows_the_same_tree_and_stages_are_ages() {
        let (a, _) = grow(ConiferParams::default(), 3, None);
        let (b, _) = grow(ConiferParams::default(), 3, None);
        let (c, _) = grow(ConiferParams::default(), 4, None);
        assert_eq!(a.skeleton(), b.skeleton());
        assert_ne!(a.skeleton(), c.skeleton());
        // A copy taken at year 10 goes on to the same tree.
        let mut early =
            Conifer::new(ConiferParams::default(), Location::new("t.lua", 1)).expect("valid");
        let ctx = RunContext {
            seed: 3,
            steps: Some(10),
            ..RunContext::default()
        };
        pge_engine::algorithm::grow(&mut early, &ctx).expect("grows");
        let mut copy = early.snapshot().expect("copyable");
        let ctx = RunContext {
            seed: 3,
            ..RunContext::default()
        };
        while copy.step(&ctx).expect("steps") == Step::Continue {}
        assert_eq!(copy.skeleton(), a.skeleton());
    }

    #[test]
    fn the_node_cap_and_the_year_cap_are_clear_errors() {
        let params = ConiferParams {
            orders: 3,
            max_nodes: 300,
            ..ConiferParams::default()
        };
        let mut c = Conifer::new(params, Location::new("t.lua", 9)).expect("valid");
        let e = run(&mut c, &RunContext::default(), &mut |_| {}).expect_err("capped");
        let e = e.to_string();
        assert!(e.starts_with("t.lua:9: pge.Conifer: at 20 years"), "{e}");
        assert!(e.contains("more than 300 nodes (maxNodes)"), "{e}");

        let mut c =
            Conifer::new(ConiferParams::default(), Location::new("t.lua", 2)).expect("valid");
        let ctx = RunContext {
            steps: Some(5000),
            ..RunContext::default()
        };
        let e = pge_engine::algorithm::grow(&mut c, &ctx).expect_err("too old");
        assert_eq!(
            e.to_string(),
            "t.lua:2: pge.Conifer: a conifer grows at most 1000 years (steps)"
        );
    }

    #[test]
    fn bad_parameters_name_themselves() {
        let params = ConiferParams {
            segment: 0.0,
            ..ConiferParams::default()
        };
        let e = Conifer::new(params, Location::new("t.lua", 2)).expect_err("bad");
        assert_eq!(
            e.to_string(),
            "t.lua:2: segment must be a number > 0, got 0"
        );
    }
}
