//! Closed triangle meshes as envelopes: reading `.obj` (a `.glb` is read by the engine's
//! `import::scene_triangles`), welding, the closedness check, and the inside test by ray
//! parity (seed 000) and distance queries through a BVH (`obvhs`) built once per mesh.

use std::collections::HashMap;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::leaf_collapser::collapse;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::PlocBuilder;
use obvhs::ray::Ray;
use pge_engine::geometry::{Model, Primitive};

/// Why a mesh cannot be an envelope.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A line of an `.obj` file could not be read.
    #[error("line {line}: {message}")]
    Obj {
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// There are no triangles.
    #[error("has no triangles")]
    Empty,
    /// An edge is used by an odd number of triangles: the mesh has a hole.
    #[error(
        "is not closed: the edge between vertices {a} and {b} ({pa}, {pb}) borders {count} triangle(s)"
    )]
    NotClosed {
        /// Welded vertex index.
        a: u32,
        /// Welded vertex index.
        b: u32,
        /// Its position.
        pa: String,
        /// Its position.
        pb: String,
        /// Triangles using it.
        count: u32,
    },
    /// A coordinate is NaN or infinite.
    #[error("has a non-finite vertex")]
    NotFinite,
}

/// A welded triangle mesh with a bounding volume hierarchy over its triangles, built once,
/// for the ray-parity inside test and the distance queries.
#[derive(Clone)]
pub struct TriMesh {
    /// Where the mesh came from (a file name, "model"), for messages.
    pub name: String,
    /// `None` when closed, else why not.
    open: Option<MeshError>,
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    min: Vec3,
    max: Vec3,
    /// The triangles' bounds, each grown by `pad` (so that rays along a face's plane and
    /// rounding in the distance bound never drop a triangle), in a BVH2.
    bvh: Bvh2,
}

impl std::fmt::Debug for TriMesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TriMesh")
            .field("name", &self.name)
            .field("vertices", &self.vertices.len())
            .field("triangles", &self.triangles.len())
            .field("closed", &self.open.is_none())
            .finish_non_exhaustive()
    }
}

impl TriMesh {
    /// A mesh from positions and triangles; equal positions are welded. Errors when empty or
    /// not finite; whether it is closed is kept for [`TriMesh::closed`].
    pub fn new(
        name: impl Into<String>,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<TriMesh, MeshError> {
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(MeshError::NotFinite);
        }
        let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
        let mut vertices = Vec::new();
        let remap: Vec<u32> = positions
            .iter()
            .map(|p| {
                // +0.0 and -0.0 are the same point.
                let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
                *weld.entry(key).or_insert_with(|| {
                    vertices.push(*p);
                    (vertices.len() - 1) as u32
                })
            })
            .collect();
        let triangles: Vec<[u32; 3]> = triangles
            .iter()
            .filter(|t| t.iter().all(|i| (*i as usize) < remap.len()))
            .map(|t| t.map(|i| remap[i as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        let open = check_closed(&vertices, &triangles).err();
        let (mut min, mut max) = (vertices[0], vertices[0]);
        for v in &vertices {
            min = min.min(*v);
            max = max.max(*v);
        }
        // Larger than the ray's nudge in `contains` and than any rounding of a distance.
        let pad = (max - min).max_element() * 1e-4;
        let boxes: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|k| Vec3A::from(vertices[k as usize]));
                Aabb::new(a.min(b).min(c) - pad, a.max(b).max(c) + pad)
            })
            .collect();
        let bvh = build_bvh(&boxes, BvhBuildParams::medium_build());
        Ok(TriMesh {
            name: name.into(),
            open,
            vertices,
            triangles,
            min,
            max,
            bvh,
        })
    }

    /// The corners of triangle `t`.
    fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|k| self.vertices[k as usize])
    }

    /// `Ok` when every edge borders an even number of triangles (the inside test needs a
    /// closed surface), else the first open edge.
    pub fn closed(&self) -> Result<(), MeshError> {
        match &self.open {
            None => Ok(()),
            Some(e) => Err(e.clone()),
        }
    }

    /// Welded vertex positions.
    #[must_use]
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Triangles (indices into [`vertices`](TriMesh::vertices)).
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Bounds `(min, max)`.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.min, self.max)
    }

    /// Whether `p` is inside: a ray toward +x crosses the surface an odd number of times.
    /// The ray is nudged off axis by a tiny fixed amount so it does not run along edges; the
    /// BVH hands over the triangles whose (padded) bounds the ray meets.
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        if p.cmplt(self.min).any() || p.cmpgt(self.max).any() {
            return false;
        }
        let extent = (self.max - self.min).max_element();
        let (py, pz) = (p.y + extent * 1.234_567e-6, p.z + extent * 2.345_678e-6);
        let ray = Ray::new_inf(Vec3A::new(p.x, py, pz), Vec3A::X);
        let mut crossings = 0u32;
        self.bvh.ray_traverse_anyhit(ray, |_, id| {
            let [a, b, c] = self.corners(self.bvh.primitive_indices[id] as usize);
            // Barycentric coordinates of (py, pz) in the triangle projected on YZ.
            let d = (b.y - a.y) * (c.z - a.z) - (c.y - a.y) * (b.z - a.z);
            if d == 0.0 {
                return;
            }
            let u = ((py - a.y) * (c.z - a.z) - (c.y - a.y) * (pz - a.z)) / d;
            let v = ((b.y - a.y) * (pz - a.z) - (py - a.y) * (b.z - a.z)) / d;
            if u < 0.0 || v < 0.0 || u + v > 1.0 {
                return;
            }
            let x = a.x + u * (b.x - a.x) + v * (c.x - a.x);
            if x > p.x {
                crossings += 1;
            }
        });
        crossings % 2 == 1
    }

    /// The squared distance from `p` to the nearest triangle: a depth-first walk of the BVH,
    /// nearer child first, skipping boxes farther than the best triangle so far. The boxes
    /// are padded, so a skipped triangle is never nearer than the result.
    #[must_use]
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        let box_d2 = |aabb: &Aabb| {
            let q = Vec3A::from(p);
            (aabb.min - q)
                .max(q - aabb.max)
                .max(Vec3A::ZERO)
                .length_squared()
        };
        let nodes = &self.bvh.nodes;
        let mut best = f32::INFINITY;
        let Some(root) = nodes.first() else {
            return best;
        };
        let mut stack = vec![(box_d2(root.aabb()), 0usize)];
        while let Some((d2, index)) = stack.pop() {
            if d2 > best {
                continue;
            }
            let node = &nodes[index];
            if node.is_leaf() {
                let first = node.first_index as usize;
                for id in &self.bvh.primitive_indices[first..first + node.prim_count as usize] {
                    let [a, b, c] = self.corners(*id as usize);
                    best = best.min(p.distance_squared(closest_on_triangle(p, a, b, c)));
                }
            } else {
                let (l, r) = (node.first_index as usize, node.first_index as usize + 1);
                let (dl, dr) = (box_d2(nodes[l].aabb()), box_d2(nodes[r].aabb()));
                // Pushed farther first, so the nearer child is walked first.
                if dl <= dr {
                    stack.push((dr, r));
                    stack.push((dl, l));
                } else {
                    stack.push((dl, l));
                    stack.push((dr, r));
                }
            }
        }
        best
    }

    /// Distance to the nearest triangle, negative inside.
    #[must_use]
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        let d = self.distance_squared(p).sqrt();
        if self.contains(p) { -d } else { d }
    }

    /// Reads a Wavefront `.obj`: `v x y z` and `f a b c ...` lines (1-based or negative
    /// indices, `a/b/c` forms; polygons are fanned). Other lines are ignored.
    pub fn parse_obj(text: &str) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), MeshError> {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let err = |message: String| MeshError::Obj {
                line: n + 1,
                message,
            };
            let mut words = line.split_whitespace();
            match words.next() {
                Some("v") => {
                    let c: Vec<f32> = words
                        .take(3)
                        .map(|w| {
                            w.parse::<f32>()
                                .map_err(|_| err(format!("'{w}' is not a number")))
                        })
                        .collect::<Result<_, _>>()?;
                    if c.len() != 3 {
                        return Err(err("a vertex needs three coordinates".into()));
                    }
                    positions.push(Vec3::new(c[0], c[1], c[2]));
                }
                Some("f") => {
                    let mut face = Vec::new();
                    for w in words {
                        let first = w.split('/').next().unwrap_or("");
                        let i: i64 = first
                            .parse()
                            .map_err(|_| err(format!("'{w}' is not a vertex index")))?;
                        let index = if i > 0 {
                            i - 1
                        } else {
                            positions.len() as i64 + i
                        };
                        if index < 0 || index >= positions.len() as i64 {
                            return Err(err(format!(
                                "vertex index {i} is out of range ({} vertices so far)",
                                positions.len()
                            )));
                        }
                        face.push(index as u32);
                    }
                    if face.len() < 3 {
                        return Err(err("a face needs at least three vertices".into()));
                    }
                    for k in 1..face.len() - 1 {
                        triangles.push([face[0], face[k], face[k + 1]]);
                    }
                }
                _ => {}
            }
        }
        Ok((positions, triangles))
    }

    /// The triangles of a model (every instance placed by its transform).
    #[must_use]
    pub fn model_triangles(model: &Model) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for inst in &model.instances {
            let mesh = &model.meshes[inst.mesh];
            if mesh.primitive != Primitive::Triangles {
                continue;
            }
            let base = positions.len() as u32;
            positions.extend(
                mesh.positions
                    .iter()
                    .map(|p| inst.transform.transform_point3(*p)),
            );
            for t in mesh.indices.chunks_exact(3) {
                triangles.push([base + t[0], base + t[1], base + t[2]]);
            }
        }
        (positions, triangles)
    }
}

/// Every undirected edge must border an even number of triangles.
fn check_closed(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Result<(), MeshError> {
    let mut edges: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut open: Vec<((u32, u32), u32)> = edges.into_iter().filter(|(_, c)| c % 2 == 1).collect();
    open.sort_unstable();
    match open.first() {
        None => Ok(()),
        Some(&((a, b), count)) => {
            let show = |v: Vec3| format!("({}, {}, {})", v.x, v.y, v.z);
            Err(MeshError::NotClosed {
                a,
                b,
                pa: show(vertices[a as usize]),
                pb: show(vertices[b as usize]),
                count,
            })
        }
    }
}

/// The point of triangle `abc` closest to `p` (Ericson, Real-Time Collision Detection 5.1.5).
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// obvhs's `build_bvh2` without its build timer: the same steps, in the same order (the
/// same tree), but no reading of `std::time::Instant`, which a host without a system clock
/// (the browser build) cannot give.
fn build_bvh(boxes: &[Aabb], config: BvhBuildParams) -> Bvh2 {
    let mut bvh = PlocBuilder::with_capacity(boxes.len()).build(
        config.ploc_search_distance,
        boxes,
        (0..boxes.len() as u32).collect::<Vec<_>>(),
        config.sort_precision,
        config.search_depth_threshold,
    );
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh, config.reinsertion_batch_ratio, None);
    collapse(
        &mut bvh,
        config.max_prims_per_leaf.clamp(1, 255),
        config.collapse_traversal_cost,
    );
    reinsertion.run(
        &mut bvh,
        config.reinsertion_batch_ratio * config.post_collapse_reinsertion_batch_ratio_multiplier,
        None,
    );
    bvh
}

#[cfg(test)]
mod tests {
    use super::*;
    use pge_engine::math;

    /// A unit cube from 0 to 1 as an .obj with quads (vertices repeated per face would weld).
    pub(crate) const CUBE_OBJ: &str = "# cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

    fn cube() -> TriMesh {
        let (p, t) = TriMesh::parse_obj(CUBE_OBJ).expect("parses");
        let m = TriMesh::new("cube", &p, &t).expect("valid");
        m.closed().expect("closed");
        m
    }

    #[test]
    fn cube_inside_test_by_parity() {
        let m = cube();
        assert_eq!(m.triangles().len(), 12);
        assert!(m.contains(Vec3::splat(0.5)));
        assert!(m.contains(Vec3::new(0.01, 0.99, 0.5)));
        assert!(!m.contains(Vec3::new(1.5, 0.5, 0.5)));
        assert!(!m.contains(Vec3::new(-0.5, 0.5, 0.5)));
        // Points on the same line as a diagonal edge are still classified.
        assert!(m.contains(Vec3::new(0.2, 0.5, 0.5)));
        assert!((m.signed_distance(Vec3::splat(0.5)) + 0.5).abs() < 1e-6);
        assert!((m.signed_distance(Vec3::new(2.0, 0.5, 0.5)) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn open_meshes_are_refused_with_the_edge() {
        let (p, mut t) = TriMesh::parse_obj(CUBE_OBJ).expect("parses");
        t.pop();
        let m = TriMesh::new("open", &p, &t).expect("usable for the vertices mode");
        let e = m.closed().expect_err("open");
        assert!(
            e.to_string().starts_with("is not closed: the edge between"),
            "{e}"
        );
        assert_eq!(
            TriMesh::new("empty", &p, &[]).expect_err("empty"),
            MeshError::Empty
        );
    }

    #[test]
    fn obj_errors_name_the_line() {
        let e = TriMesh::parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 7\n").expect_err("bad index");
        assert_eq!(
            e.to_string(),
            "line 3: vertex index 7 is out of range (2 vertices so far)"
        );
        let e = TriMesh::parse_obj("v 0 zero 0\n").expect_err("bad number");
        assert_eq!(e.to_string(), "line 1: 'zero' is not a number");
        let (p, t) = TriMesh::parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3/1/1 -2/2/2 -1/3/3\n")
            .expect("relative");
        assert_eq!((p.len(), t), (3, vec![[0, 1, 2]]));
    }

    #[test]
    fn split_vertices_are_welded() {
        // Two triangles of a square with their own copies of the shared edge.
        let p = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::X,
            Vec3::ONE.with_z(0.0),
            Vec3::Y,
        ];
        let m = TriMesh::new("square", &p, &[[0, 1, 2], [3, 4, 5]]).expect("ok");
        assert_eq!(m.vertices().len(), 4);
    }

    /// A closed, lumpy ball: a UV sphere with `n` rings whose radius varies with direction.
    fn lumpy_ball(n: u32) -> TriMesh {
        let mut p = vec![Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        for i in 1..n {
            let theta = std::f32::consts::PI * i as f32 / n as f32;
            for j in 0..2 * n {
                let phi = std::f32::consts::PI * j as f32 / n as f32;
                let r = 1.0 + 0.3 * math::sin(3.0 * phi) * math::sin(2.0 * theta);
                p.push(
                    r * Vec3::new(
                        math::sin(theta) * math::cos(phi),
                        -math::cos(theta),
                        math::sin(theta) * math::sin(phi),
                    ),
                );
            }
        }
        let ring = |i: u32, j: u32| 2 + (i - 1) * 2 * n + j % (2 * n);
        let mut t = Vec::new();
        for j in 0..2 * n {
            t.push([0, ring(1, j), ring(1, j + 1)]);
            t.push([1, ring(n - 1, j + 1), ring(n - 1, j)]);
            for i in 1..n - 1 {
                t.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                t.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
        }
        let m = TriMesh::new("ball", &p, &t).expect("valid");
        m.closed().expect("closed");
        m
    }

    #[test]
    fn bvh_queries_agree_with_testing_every_triangle() {
        let m = lumpy_ball(12);
        let mut rng = rand_mt::Mt64::new(5);
        let mut inside = 0;
        for _ in 0..2000 {
            let p = Vec3::new(
                pge_engine::random::uniform24(&mut rng),
                pge_engine::random::uniform24(&mut rng),
                pge_engine::random::uniform24(&mut rng),
            ) * 3.0
                - 1.5;
            let brute = m
                .triangles()
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|k| m.vertices()[k as usize]);
                    p.distance_squared(closest_on_triangle(p, a, b, c))
                })
                .fold(f32::INFINITY, f32::min);
            assert_eq!(m.distance_squared(p), brute, "at {p}");
            // Parity by every triangle, as the inside test did before the BVH.
            let extent = (m.max - m.min).max_element();
            let (py, pz) = (p.y + extent * 1.234_567e-6, p.z + extent * 2.345_678e-6);
            let crossings = (0..m.triangles().len())
                .filter(|t| {
                    let [a, b, c] = m.corners(*t);
                    let d = (b.y - a.y) * (c.z - a.z) - (c.y - a.y) * (b.z - a.z);
                    let u = ((py - a.y) * (c.z - a.z) - (c.y - a.y) * (pz - a.z)) / d;
                    let v = ((b.y - a.y) * (pz - a.z) - (py - a.y) * (b.z - a.z)) / d;
                    d != 0.0
                        && u >= 0.0
                        && v >= 0.0
                        && u + v <= 1.0
                        && a.x + u * (b.x - a.x) + v * (c.x - a.x) > p.x
                })
                .count();
            let in_bounds = !(p.cmplt(m.min).any() || p.cmpgt(m.max).any());
            assert_eq!(m.contains(p), in_bounds && crossings % 2 == 1, "at {p}");
            inside += usize::from(m.contains(p));
        }
        assert!(inside > 200 && inside < 1800, "{inside} of 2000 inside");
    }

    #[test]
    fn closest_points() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let inner = closest_on_triangle(Vec3::new(0.2, 0.2, 1.0), a, b, c);
        assert!(inner.distance(Vec3::new(0.2, 0.2, 0.0)) < 1e-6, "{inner}");
        assert_eq!(closest_on_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c), a);
        assert_eq!(
            closest_on_triangle(Vec3::new(2.0, 2.0, 0.0), a, b, c),
            Vec3::new(0.5, 0.5, 0.0)
        );
    }
}
