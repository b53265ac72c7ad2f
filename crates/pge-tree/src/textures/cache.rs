//! The texture cache: every set generated once per parameter set and process.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use super::{BarkParams, LeafParams, TextureSet, bark_set, leaf_set};
use crate::TreeError;

type Cell = Arc<OnceLock<Result<Arc<TextureSet>, GenerateError>>>;

/// Why a set could not be made, kept in its cell and handed to every asker (hence shared).
#[derive(Clone, Debug, thiserror::Error)]
enum GenerateError {
    /// The texture threads could not start.
    #[error("cannot start the texture threads: {0}")]
    Threads(Arc<dyn std::error::Error + Send + Sync>),
    /// Making the set failed.
    #[error("{0}")]
    Made(Arc<TreeError>),
}

/// Texture sets by parameter set, each generated once however many sessions ask for it at
/// the same time: the first asker generates, the others wait for its result (one
/// generate-once cell per key, the map locked only to find the cell).
#[derive(Default)]
pub struct TextureCache {
    cells: Mutex<HashMap<String, Cell>>,
    generated: AtomicU64,
}

impl TextureCache {
    /// The process's cache, shared by every session and tree.
    pub fn global() -> &'static TextureCache {
        static CACHE: OnceLock<TextureCache> = OnceLock::new();
        CACHE.get_or_init(TextureCache::default)
    }

    /// How many sets this cache has generated (not counting the ones it handed out again).
    pub fn generated(&self) -> u64 {
        self.generated.load(Ordering::Relaxed)
    }

    /// The bark set of `params`, generated on first use.
    pub fn bark(&self, params: &BarkParams) -> Result<Arc<TextureSet>, TreeError> {
        self.get(format!("bark {params:?}"), || bark_set(params))
    }

    /// The leaf set of `params`, generated on first use.
    pub fn leaf(&self, params: &LeafParams) -> Result<Arc<TextureSet>, TreeError> {
        self.get(format!("leaf {params:?}"), || leaf_set(params))
    }

    fn get(
        &self,
        key: String,
        make: impl FnOnce() -> Result<TextureSet, TreeError> + Send,
    ) -> Result<Arc<TextureSet>, TreeError> {
        let cell = {
            let mut cells = self.cells.lock().unwrap_or_else(|e| e.into_inner());
            cells.entry(key).or_default().clone()
        };
        cell.get_or_init(|| {
            self.generated.fetch_add(1, Ordering::Relaxed);
            generate(make).map(Arc::new)
        })
        .clone()
        .map_err(|e| TreeError::Generated(e.to_string()))
    }
}

/// Runs `make` on the texture threads: a pool of their own (as many as the caller's pool),
/// reached through a thread outside every pool. Generating a set fills its rows with pool
/// work while the cache's cell for it is held; a thread of the caller's pool waiting there
/// would run other jobs of that pool meanwhile, and one of them (another variant of a
/// forest) could ask the same cell for the same set: the thread would wait for itself. The
/// texture threads run nothing but the set's own work, and the caller only waits. A caller
/// alone in its pool (`--threads 1`, a browser without threads) makes the set itself: its
/// pool work runs in order on this thread, which never picks up another job meanwhile.
fn generate(
    make: impl FnOnce() -> Result<TextureSet, TreeError> + Send,
) -> Result<TextureSet, GenerateError> {
    if rayon::current_num_threads() == 1 {
        return make().map_err(|e| GenerateError::Made(Arc::new(e)));
    }
    static POOL: OnceLock<Result<rayon::ThreadPool, GenerateError>> = OnceLock::new();
    let pool = POOL
        .get_or_init(|| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(rayon::current_num_threads())
                .thread_name(|i| format!("pge-textures-{i}"))
                .build()
                .map_err(|e| GenerateError::Threads(Arc::new(e)))
        })
        .as_ref()
        .map_err(Clone::clone)?;
    std::thread::scope(|scope| {
        let made = std::thread::Builder::new()
            .name("pge-textures".into())
            .spawn_scoped(scope, || pool.install(make))
            .map_err(|e| GenerateError::Threads(Arc::new(e)))?
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        made.map_err(|e| GenerateError::Made(Arc::new(e)))
    })
}

/// The bark set of `params` from the process's cache.
pub fn bark_textures(params: &BarkParams) -> Result<Arc<TextureSet>, TreeError> {
    TextureCache::global().bark(params)
}

/// The leaf set of `params` from the process's cache.
pub fn leaf_textures(params: &LeafParams) -> Result<Arc<TextureSet>, TreeError> {
    TextureCache::global().leaf(params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::textures::test_support::bark;
    use crate::textures::{BarkStyle, LeafShape};
    use rayon::prelude::*;

    #[test]
    fn sets_are_made_once_per_parameter_set_across_threads() {
        let cache = TextureCache::default();
        let params = [
            bark(BarkStyle::Furrowed, 32),
            bark(BarkStyle::Plated, 32),
            BarkParams {
                color: [0.3, 0.3, 0.3, 1.0],
                ..bark(BarkStyle::Furrowed, 32)
            },
        ];
        let leaf = LeafParams {
            shape: LeafShape::Lobed,
            size: 32,
            per_card: 1,
        };
        // 24 variants, as a forest builds them: in parallel, asking for the same sets.
        let sets: Vec<Vec<Arc<TextureSet>>> = (0..24)
            .into_par_iter()
            .map(|i| {
                vec![
                    cache.bark(&params[i % 3]).expect("bark"),
                    cache.leaf(&leaf).expect("leaf"),
                ]
            })
            .collect();
        assert_eq!(cache.generated(), 4, "three bark sets and one leaf set");
        for (i, s) in sets.iter().enumerate() {
            assert!(
                Arc::ptr_eq(&s[0], &sets[i % 3][0]),
                "variant {i} shares its bark"
            );
            assert!(Arc::ptr_eq(&s[1], &sets[0][1]));
        }
        assert!(
            !Arc::ptr_eq(&sets[0][0], &sets[2][0]),
            "another colour, another set"
        );
        // A new cache makes the same bytes: the sets depend on their parameters only.
        let again = TextureCache::default().bark(&params[1]).expect("bark");
        assert_eq!(again.color.encoded, sets[1][0].color.encoded);
        assert_eq!(again.normal.encoded, sets[1][0].normal.encoded);
    }

    #[test]
    fn a_pool_thread_waiting_inside_a_set_never_asks_for_that_set_itself() {
        use std::sync::mpsc;
        use std::time::Duration;

        // The set's maker waits for pool work another thread of the pool took; meanwhile
        // other askers of the same set are queued on that pool. A thread that holds the
        // set's cell and picks one of them up while it waits would wait for itself.
        let cache = Arc::new(TextureCache::default());
        let pool = Arc::new(
            rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .build()
                .expect("pool"),
        );
        let (inside_tx, inside) = mpsc::channel();
        let make = move || {
            // The first half on this thread, the second, longer, taken by the other thread
            // while the first sleeps: it says so, and the other askers are queued then.
            rayon::join(
                || std::thread::sleep(Duration::from_millis(50)),
                || {
                    let _ = inside_tx.send(());
                    std::thread::sleep(Duration::from_millis(250));
                },
            );
            bark_set(&bark(BarkStyle::Furrowed, 16))
        };
        let (done_tx, done) = mpsc::channel();
        let ask = |make: Box<dyn FnOnce() -> Result<TextureSet, TreeError> + Send>| {
            let (cache, done_tx) = (cache.clone(), done_tx.clone());
            pool.spawn(move || {
                let set = cache.get("deadlock".into(), make);
                let _ = done_tx.send(set.is_ok());
            });
        };
        ask(Box::new(make));
        inside
            .recv_timeout(Duration::from_secs(60))
            .expect("the set is being made");
        for _ in 0..8 {
            ask(Box::new(|| unreachable!("the set is made once")));
        }
        // A watchdog, not a measure: the asks take a third of a second.
        for i in 0..9 {
            match done.recv_timeout(Duration::from_secs(120)) {
                Ok(ok) => assert!(ok, "ask {i} failed"),
                Err(_) => panic!("deadlock: {i} of 9 asks answered in two minutes"),
            }
        }
        assert_eq!(cache.generated(), 1);
    }

    #[test]
    fn a_forest_of_24_variants_built_in_parallel_shares_one_set_per_parameter_set() {
        use crate::{LeafOptions, MeshOptions, TreeOptions, build_tree};
        use glam::Vec3;
        use pge_engine::geometry::Skeleton;

        let mut skeleton = Skeleton::new();
        let root = skeleton.push(Vec3::ZERO, None, 0.0, 0);
        let fork = skeleton.push(Vec3::Y, Some(root), 0.0, 0);
        skeleton.push(Vec3::new(-0.4, 1.6, 0.0), Some(fork), 0.0, 1);
        skeleton.push(Vec3::new(0.4, 1.6, 0.1), Some(fork), 0.0, 1);
        // Two bark colours among the variants; sizes no other test asks for, so this test
        // sees its own sets in the process's cache.
        let options = |i: usize| TreeOptions {
            mesh: MeshOptions {
                color: [0.31, 0.2 + 0.1 * (i % 2) as f32, 0.1, 1.0],
                texture_size: 40,
                ..MeshOptions::default()
            },
            leaves: Some(LeafOptions {
                texture_size: 40,
                ..LeafOptions::default()
            }),
            lod: None,
        };
        // Every variant through build_tree, in parallel as a forest builds them.
        let trees: Vec<_> = (0..24)
            .into_par_iter()
            .map(|i| build_tree(&skeleton, &options(i), i as u64).expect("tree"))
            .collect();
        let maps = |i: usize, mesh: usize| {
            let m = &trees[i].meshes[mesh].material;
            [&m.texture, &m.normal_texture, &m.metallic_roughness_texture]
                .map(|t| t.clone().expect("a procedural map"))
        };
        for i in 0..24 {
            for (a, b) in maps(i, 0).iter().zip(maps(i % 2, 0).iter()) {
                assert!(Arc::ptr_eq(a, b), "variant {i}: its colour's one bark set");
            }
            for (a, b) in maps(i, 1).iter().zip(maps(0, 1).iter()) {
                assert!(Arc::ptr_eq(a, b), "variant {i}: the one leaf set");
            }
        }
        assert!(
            !Arc::ptr_eq(&maps(0, 0)[0], &maps(1, 0)[0]),
            "two colours, two sets"
        );
    }
}
