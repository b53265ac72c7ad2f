//! A forest's plan ([`forest::plan`]) made off the render thread.
//!
//! Planning a frame of a 100,000-tree forest (culling every instance, the Scaling of each
//! variant's leaves, grouping by band, gathering the instances' matrices in band order)
//! takes longer than a frame may. So the render thread asks a planner thread for the plan of
//! its latest camera and keeps drawing the last plan it received until the new one is ready:
//! a frame never waits for a plan. At most one request is in flight: when a plan arrives,
//! the next request is for the camera of that moment, so a camera that moves faster than
//! plans are made skips the cameras in between.
//!
//! Each uploaded scene is an *epoch* ([`Planner::reset`]): its meshes and their instance
//! buffers. A plan made for an earlier epoch is dropped when it arrives, never drawn with
//! the buffers of a newer scene. Within an epoch, each plan says which instances changed
//! since the previous one ([`Planned::changed`]), so only those are written to the GPU.

use pge_engine::math;
use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::forest::{self, Detail, ForestMesh, Plan, View};
use super::scene::Scene;

/// The forest meshes of one uploaded scene, as the planner reads them.
#[derive(Debug)]
pub struct ForestSet {
    scene: Arc<Scene>,
    /// Per forest mesh: its index in `scene.meshes` and what it can draw.
    meshes: Vec<(usize, Detail)>,
}

impl ForestSet {
    /// The forest meshes `meshes` (index in `scene.meshes`, detail) of `scene`; indices
    /// out of range are left out.
    #[must_use]
    pub fn new(scene: Arc<Scene>, meshes: Vec<(usize, Detail)>) -> ForestSet {
        let meshes = meshes
            .into_iter()
            .filter(|(k, _)| *k < scene.meshes.len())
            .collect();
        ForestSet { scene, meshes }
    }

    /// The meshes as [`forest::plan`] takes them, in the order given to [`ForestSet::new`].
    fn forest_meshes(&self) -> Vec<ForestMesh<'_>> {
        self.meshes
            .iter()
            .map(|(k, detail)| {
                let mesh = &self.scene.meshes[*k];
                ForestMesh {
                    instances: &mesh.instances,
                    centre: mesh.sphere.0,
                    radius: mesh.sphere.1,
                    detail,
                }
            })
            .collect()
    }

    /// Whether there is anything to plan.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.meshes.is_empty()
    }
}

/// What a plan is made for: a camera and a leaf budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Request {
    /// The camera.
    pub view: View,
    /// The leaf budget T.
    pub budget: u64,
}

/// While the camera moves, the plan asked for last is drawn on as long as the camera looks
/// within this angle (radians) of the same direction, from within this share of its
/// distance to the model of the same eye: the plan's margin
/// ([`forest::MOVING_MARGIN`]) covers that much turning.
pub const MOVING_REUSE: f32 = 0.026;

impl Request {
    /// Whether a moving frame for `other` may draw the plan made for `self`: the same
    /// budget, a view direction within [`MOVING_REUSE`] radians, and an eye moved less than
    /// [`MOVING_REUSE`] times `distance` (the eye's distance to what it looks at).
    #[must_use]
    pub fn close_to(&self, other: &Request, distance: f32) -> bool {
        // A perspective view_proj's last row is the view direction: clip w is the depth.
        let forward = |r: &Request| r.view.view_proj.row(3).truncate().normalize_or_zero();
        let (a, b) = (forward(self), forward(other));
        self.budget == other.budget
            && a != glam::Vec3::ZERO
            && a.dot(b) >= math::cos(MOVING_REUSE)
            && self.view.eye.distance(other.view.eye) <= MOVING_REUSE * distance
    }
}

/// A finished plan.
#[derive(Debug)]
pub struct Planned {
    /// The scene it was made for ([`Planner::reset`]).
    pub epoch: u64,
    /// The camera and budget it was made for.
    pub request: Request,
    /// The draws of every forest mesh.
    pub plan: Plan,
    /// Per forest mesh, the matrices of its drawn instances in the plan's order: what its
    /// instance buffer holds.
    pub matrices: Vec<Vec<[f32; 16]>>,
    /// Per forest mesh, the positions of `matrices` that differ from the previous plan of
    /// the same epoch (all of them for the first); empty when none do.
    pub changed: Vec<Range<usize>>,
    /// How long planning took on the planner thread.
    pub took: Duration,
}

struct Job {
    epoch: u64,
    set: Arc<ForestSet>,
    request: Request,
}

/// The render thread's side of the planner thread.
pub struct Planner {
    jobs: Option<Sender<Job>>,
    results: Receiver<Planned>,
    thread: Option<JoinHandle<()>>,
    /// The epoch of the current scene, shared with the thread so it skips older jobs.
    epoch: Arc<AtomicU64>,
    set: Option<Arc<ForestSet>>,
    /// A request of the current epoch is being planned.
    in_flight: bool,
    /// The request of the plan last handed out in this epoch.
    applied: Option<Request>,
    /// The request last asked for in this epoch.
    asked: Option<Request>,
}

impl Planner {
    /// Starts the planner thread; `wake` is called whenever a plan is ready (to ask the
    /// window for a frame).
    #[must_use]
    pub fn new(wake: impl Fn() + Send + 'static) -> Planner {
        let (jobs, inbox) = channel::<Job>();
        let (outbox, results) = channel();
        let epoch = Arc::new(AtomicU64::new(0));
        let current = epoch.clone();
        let thread = std::thread::Builder::new()
            .name("pge-forest-plan".into())
            .spawn(move || plan_jobs(&inbox, &outbox, &current, &wake))
            .ok();
        Planner {
            jobs: thread.is_some().then_some(jobs),
            results,
            thread,
            epoch,
            set: None,
            in_flight: false,
            applied: None,
            asked: None,
        }
    }

    /// A new scene was uploaded: plans are made for `set` from now on, and plans still
    /// coming for the previous scene are dropped.
    pub fn reset(&mut self, set: Option<Arc<ForestSet>>) {
        self.epoch.fetch_add(1, Ordering::SeqCst);
        self.set = set.filter(|s| !s.is_empty());
        self.in_flight = false;
        self.applied = None;
        self.asked = None;
    }

    /// The request last asked for since the last [`Planner::reset`].
    #[must_use]
    pub fn asked(&self) -> Option<&Request> {
        self.asked.as_ref()
    }

    /// The current epoch.
    #[must_use]
    pub fn epoch(&self) -> u64 {
        self.epoch.load(Ordering::SeqCst)
    }

    /// The plan that has arrived for the current scene since the last call, if any (to be
    /// drawn from now on). Never waits.
    pub fn poll(&mut self) -> Option<Planned> {
        self.receive(false)
    }

    /// Like [`Planner::poll`] then [`Planner::ask`], but waits for the plan of `want` (for
    /// tests, and for nothing else: frames never wait).
    #[cfg(test)]
    pub fn wait_for(&mut self, want: Request) -> Option<Planned> {
        let mut last = None;
        loop {
            if let Some(p) = self.receive(false) {
                last = Some(p);
            }
            self.ask(want);
            if !self.in_flight {
                return last;
            }
            if let Some(p) = self.receive(true) {
                last = Some(p);
            }
        }
    }

    /// Whether the last plan handed out was made for `want` (nothing more will come for it;
    /// nothing ever comes when the planner thread could not be started).
    #[must_use]
    pub fn settled(&self, want: &Request) -> bool {
        self.set.is_none() || self.jobs.is_none() || self.applied.as_ref() == Some(want)
    }

    /// Asks for the plan of `want` (the camera and budget of the frame being drawn) unless
    /// one is being made or the last one was for it.
    pub fn ask(&mut self, want: Request) {
        let (Some(set), Some(jobs)) = (&self.set, &self.jobs) else {
            return;
        };
        if self.in_flight || self.applied == Some(want) {
            return;
        }
        let job = Job {
            epoch: self.epoch(),
            set: set.clone(),
            request: want,
        };
        self.in_flight = jobs.send(job).is_ok();
        if self.in_flight {
            self.asked = Some(want);
        }
    }

    /// The next plan of the current epoch that has arrived (waiting for one if `block` and
    /// one is in flight); plans of earlier epochs are dropped.
    fn receive(&mut self, block: bool) -> Option<Planned> {
        loop {
            let planned = if block && self.in_flight {
                self.results.recv().ok()
            } else {
                self.results.try_recv().ok()
            };
            let Some(planned) = planned else {
                // The thread is gone (it cannot be, short of a panic): stop waiting.
                if block {
                    self.in_flight = false;
                }
                return None;
            };
            if planned.epoch == self.epoch() {
                self.in_flight = false;
                self.applied = Some(planned.request);
                return Some(planned);
            }
        }
    }
}

impl Drop for Planner {
    fn drop(&mut self) {
        self.jobs = None; // closes the channel: the thread ends
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// The planner thread: plans each job of the current epoch, in order, and says which
/// instances changed since its previous plan of the same epoch.
fn plan_jobs(inbox: &Receiver<Job>, outbox: &Sender<Planned>, epoch: &AtomicU64, wake: &dyn Fn()) {
    let mut previous: Option<(u64, Vec<Vec<u32>>)> = None;
    let mut buffers = forest::PlanBuffers::default();
    while let Ok(job) = inbox.recv() {
        if job.epoch != epoch.load(Ordering::SeqCst) {
            continue; // a newer scene was uploaded
        }
        let t0 = Instant::now();
        let meshes = job.set.forest_meshes();
        let plan = forest::plan(&meshes, &job.request.view, job.request.budget, &mut buffers);
        let matrices: Vec<Vec<[f32; 16]>> = meshes
            .iter()
            .zip(&plan.meshes)
            .map(|(m, p)| p.order.iter().map(|&i| m.instances[i as usize]).collect())
            .collect();
        let changed = plan
            .meshes
            .iter()
            .enumerate()
            .map(|(k, p)| match &previous {
                Some((e, orders)) if *e == job.epoch => {
                    changed_range(orders.get(k).map_or(&[][..], Vec::as_slice), &p.order)
                }
                _ => 0..p.order.len(),
            })
            .collect();
        previous = Some((
            job.epoch,
            plan.meshes.iter().map(|p| p.order.clone()).collect(),
        ));
        let planned = Planned {
            epoch: job.epoch,
            request: job.request,
            plan,
            matrices,
            changed,
            took: t0.elapsed(),
        };
        if outbox.send(planned).is_err() {
            return;
        }
        wake();
    }
}

/// The positions of `new` that differ from `old` at the same position (or are beyond its
/// end), as one range from the first to the last; empty when none do.
#[must_use]
pub fn changed_range(old: &[u32], new: &[u32]) -> Range<usize> {
    let differs = |i: usize| old.get(i) != new.get(i);
    match (0..new.len()).find(|&i| differs(i)) {
        Some(first) => {
            let last = (first..new.len())
                .rev()
                .find(|&i| differs(i))
                .unwrap_or(first);
            first..last + 1
        }
        None => 0..0,
    }
}

#[cfg(test)]
mod tests {
    use glam::{Mat4, Vec3};

    use super::*;
    use crate::VERTEX_FLOATS;
    use crate::scene::{SceneMesh, SceneStats};

    /// A scene with one rigid forest mesh of `n` instances along -Z, `offset` metres apart.
    fn scene(n: usize, offset: f32) -> Arc<Scene> {
        let instances = (0..n)
            .map(|i| {
                Mat4::from_translation(Vec3::new(0.0, 0.0, -5.0 - offset * i as f32))
                    .to_cols_array()
            })
            .collect();
        let mesh = SceneMesh {
            vertices: vec![0.0; 3 * VERTEX_FLOATS],
            indices: vec![0, 1, 2],
            lines: false,
            instances,
            base_color: [1.0; 4],
            texture: None,
            normal_texture: None,
            alpha_cutoff: None,
            double_sided: false,
            transmission: None,
            is_leaf: false,
            coarse: None,
            lod: None,
            forest: true,
            sphere: (Vec3::ZERO, 1.0),
        };
        Arc::new(Scene {
            meshes: vec![mesh],
            skeleton: Vec::new(),
            bounds: None,
            stats: SceneStats::default(),
            environment: None,
        })
    }

    fn set(scene: Arc<Scene>) -> Arc<ForestSet> {
        let detail = Detail::Rigid {
            full: 3,
            coarse: None,
        };
        Arc::new(ForestSet::new(scene, vec![(0, detail)]))
    }

    fn request(z: f32, budget: u64) -> Request {
        let proj = Mat4::perspective_rh(0.8, 1.0, 0.1, 10_000.0);
        let eye = Vec3::new(0.0, 0.0, z);
        Request {
            view: View {
                eye,
                view_proj: proj * Mat4::look_at_rh(eye, eye - Vec3::Z, Vec3::Y),
            },
            budget,
        }
    }

    #[test]
    fn a_plan_for_an_earlier_scene_is_never_handed_out() {
        let mut planner = Planner::new(|| {});
        planner.reset(Some(set(scene(1000, 1.0))));
        let old_epoch = planner.epoch();
        // Ask for a plan of the first scene, then upload a smaller one before it arrives.
        planner.ask(request(0.0, 1_000_000));
        planner.reset(Some(set(scene(10, 1.0))));
        assert_ne!(planner.epoch(), old_epoch);
        let planned = planner
            .wait_for(request(0.0, 1_000_000))
            .expect("a plan for the new scene");
        assert_eq!(planned.epoch, planner.epoch());
        // Its layout is the new scene's: 10 instances, indices into the new buffer.
        assert_eq!(planned.matrices[0].len(), 10);
        assert!(planned.plan.meshes[0].order.iter().all(|&i| i < 10));
        // Nothing of the old scene comes after it.
        std::thread::sleep(Duration::from_millis(50));
        assert!(planner.poll().is_none());
        assert!(planner.settled(&request(0.0, 1_000_000)));
    }

    #[test]
    fn after_a_new_scene_nothing_is_settled_until_its_own_plan_arrives() {
        let mut planner = Planner::new(|| {});
        let want = request(0.0, 3_000);
        planner.reset(Some(set(scene(100, 1.0))));
        planner.wait_for(want).expect("a plan of the first scene");
        assert!(planner.settled(&want));
        // The same camera and budget for a new scene: the plan drawn is the old scene's.
        planner.reset(Some(set(scene(50, 1.0))));
        assert!(!planner.settled(&want));
        planner.ask(want);
        assert!(!planner.settled(&want), "asked, not arrived");
        let planned = planner.wait_for(want).expect("a plan of the new scene");
        assert_eq!(planned.epoch, planner.epoch());
        assert!(planner.settled(&want));
        // A scene without a forest has nothing to wait for.
        planner.reset(None);
        assert!(planner.settled(&want));
    }

    #[test]
    fn the_plan_for_a_camera_is_the_same_every_time() {
        let mut a = Planner::new(|| {});
        let mut b = Planner::new(|| {});
        let s = set(scene(5000, 0.5));
        a.reset(Some(s.clone()));
        b.reset(Some(s));
        // b reaches the camera after a smaller budget (its buffer holds that plan's
        // instances, the nearest of the same); a directly.
        let before = b.wait_for(request(-20.0, 1_900)).expect("plan");
        let mut buffer = before.matrices[0].clone();
        let want = request(-20.0, 2_000);
        let pa = a.wait_for(want).expect("plan");
        let pb = b.wait_for(want).expect("plan");
        assert_eq!(pa.plan, pb.plan);
        assert_eq!(pa.matrices, pb.matrices);
        assert_eq!(pa.request, want);
        assert!(!pa.plan.meshes[0].order.is_empty());
        // a's first plan writes everything; b writes only what changed, and that is enough.
        assert_eq!(pa.changed[0], 0..pa.matrices[0].len());
        assert!(
            pb.changed[0].len() < pb.matrices[0].len(),
            "{:?}",
            pb.changed[0]
        );
        buffer.resize(pb.matrices[0].len().max(buffer.len()), [0.0; 16]);
        buffer[pb.changed[0].clone()].copy_from_slice(&pb.matrices[0][pb.changed[0].clone()]);
        assert_eq!(&buffer[..pb.matrices[0].len()], pb.matrices[0].as_slice());
    }

    #[test]
    fn one_request_is_in_flight_and_the_latest_camera_is_asked_for_next() {
        let mut planner = Planner::new(|| {});
        planner.reset(Some(set(scene(20_000, 0.1))));
        let first = request(0.0, 5_000);
        planner.ask(first);
        assert!(planner.in_flight);
        planner.ask(request(1.0, 5_000));
        assert!(planner.in_flight);
        // The first plan comes; the second camera is asked for only then.
        let planned = planner.wait_for(request(1.0, 5_000)).expect("plan");
        assert_eq!(planned.request, request(1.0, 5_000));
        assert!(planner.settled(&request(1.0, 5_000)));
        assert!(!planner.settled(&first));
    }

    #[test]
    fn a_moving_camera_reuses_a_plan_while_it_turns_little() {
        let proj = Mat4::perspective_rh(0.8, 1.0, 0.1, 10_000.0);
        // Orbiting a target 100 m away by `angle` radians.
        let orbit = |angle: f32, budget| {
            let target = Vec3::new(0.0, 0.0, -100.0);
            let eye = target + 100.0 * Vec3::new(math::sin(angle), 0.0, math::cos(angle));
            Request {
                view: View {
                    eye,
                    view_proj: proj * Mat4::look_at_rh(eye, target, Vec3::Y),
                },
                budget,
            }
        };
        let at = orbit(0.0, 500);
        assert!(at.close_to(&at, 100.0));
        assert!(at.close_to(&orbit(0.01, 500), 100.0));
        assert!(orbit(0.01, 500).close_to(&at, 100.0));
        assert!(!at.close_to(&orbit(0.05, 500), 100.0), "turned too far");
        assert!(!at.close_to(&orbit(0.01, 600), 100.0), "another budget");
        // Zooming in by 10 % keeps the direction but moves the eye 10 m.
        let mut zoomed = at;
        zoomed.view.eye.z -= 10.0;
        zoomed.view.view_proj =
            proj * Mat4::look_at_rh(zoomed.view.eye, Vec3::new(0.0, 0.0, -100.0), Vec3::Y);
        assert!(!at.close_to(&zoomed, 100.0));
        assert!(at.close_to(&zoomed, 1000.0), "small for a far model");
    }

    #[test]
    fn changed_ranges_cover_every_difference() {
        assert_eq!(changed_range(&[1, 2, 3], &[1, 2, 3]), 0..0);
        assert_eq!(changed_range(&[1, 2, 3], &[1, 5, 3]), 1..2);
        assert_eq!(changed_range(&[1, 2, 3], &[1, 2, 3, 4]), 3..4);
        assert_eq!(changed_range(&[1, 2, 3, 4], &[1, 2]), 0..0);
        assert_eq!(changed_range(&[], &[7, 8]), 0..2);
        assert_eq!(changed_range(&[1, 2, 3, 4], &[0, 2, 3, 9]), 0..4);
    }
}
