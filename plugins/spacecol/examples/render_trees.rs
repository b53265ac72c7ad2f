//! Grows tree scripts and renders each to a PNG with a small software rasterizer (z-buffer,
//! textures with alpha mask, vertex colours, two lights), so trees can be looked at on a
//! machine without a GPU. Only `pge.SpaceColonization` and `pge.shape` are available to the
//! scripts here (the full `pge` command has every plugin).
//!
//! ```text
//! cargo run --release -p pge-spacecol --example render_trees -- OUT_DIR scripts/species/*.lua
//! ```

use pge_engine::math;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec2, Vec3, Vec4};
use pge_engine::geometry::{AlphaMode, Model};
use pge_engine::{Engine, SessionOptions};
use pge_spacecol::SpaceColonizationPlugin;

const SIZE: usize = 640;

struct Image {
    rgb: Vec<[f32; 3]>,
    depth: Vec<f32>,
}

fn decode(png: &[u8]) -> Option<image::RgbaImage> {
    image::load_from_memory(png).ok().map(|i| i.to_rgba8())
}

fn sample(tex: &image::RgbaImage, uv: Vec2) -> Vec4 {
    let (w, h) = tex.dimensions();
    let x = (uv.x.rem_euclid(1.0) * w as f32) as u32 % w;
    let y = (uv.y.rem_euclid(1.0) * h as f32) as u32 % h;
    let p = tex.get_pixel(x, y);
    let lin = |c: u8| math::powf(c as f32 / 255.0, 2.2);
    Vec4::new(lin(p[0]), lin(p[1]), lin(p[2]), p[3] as f32 / 255.0)
}

fn render(model: &Model, yaw: f32) -> Image {
    let (lo, hi) = model.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let centre = (lo + hi) * 0.5;
    let radius = (hi - lo).length() * 0.5;
    let eye = centre + Vec3::new(math::sin(yaw), 0.25, math::cos(yaw)).normalize() * radius * 2.6;
    let view = Mat4::look_at_rh(eye, centre, Vec3::Y);
    let proj = Mat4::perspective_rh(40f32.to_radians(), 1.0, radius * 0.1, radius * 10.0);
    let vp = proj * view;
    let mut img = Image {
        rgb: vec![[0.0; 3]; SIZE * SIZE],
        depth: vec![f32::INFINITY; SIZE * SIZE],
    };
    for (i, px) in img.rgb.iter_mut().enumerate() {
        let t = (i / SIZE) as f32 / SIZE as f32;
        *px = [0.55 + 0.3 * t, 0.7 + 0.2 * t, 0.9];
    }
    let sun = Vec3::new(0.4, 0.8, 0.5).normalize();
    for inst in &model.instances {
        let mesh = &model.meshes[inst.mesh];
        let tex = mesh
            .material
            .texture
            .as_ref()
            .and_then(|t| decode(&t.encoded));
        let cutoff = match mesh.material.alpha {
            AlphaMode::Mask(c) => Some(c),
            _ => None,
        };
        let base = Vec4::from_array(mesh.material.base_color);
        let screen: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| {
                let c = vp * inst.transform * p.extend(1.0);
                let n = c.truncate() / c.w;
                Vec3::new(
                    (n.x * 0.5 + 0.5) * SIZE as f32,
                    (0.5 - n.y * 0.5) * SIZE as f32,
                    c.w,
                )
            })
            .collect();
        for t in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            let (pa, pb, pc) = (screen[a], screen[b], screen[c]);
            if pa.z <= 0.0 || pb.z <= 0.0 || pc.z <= 0.0 {
                continue;
            }
            let area = (pb.x - pa.x) * (pc.y - pa.y) - (pc.x - pa.x) * (pb.y - pa.y);
            if area.abs() < 1e-9 {
                continue;
            }
            let x0 = pa.x.min(pb.x).min(pc.x).floor().max(0.0) as usize;
            let x1 = (pa.x.max(pb.x).max(pc.x).ceil() as usize).min(SIZE - 1);
            let y0 = pa.y.min(pb.y).min(pc.y).floor().max(0.0) as usize;
            let y1 = (pa.y.max(pb.y).max(pc.y).ceil() as usize).min(SIZE - 1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
                    let w0 = ((pb.x - fx) * (pc.y - fy) - (pc.x - fx) * (pb.y - fy)) / area;
                    let w1 = ((pc.x - fx) * (pa.y - fy) - (pa.x - fx) * (pc.y - fy)) / area;
                    let w2 = 1.0 - w0 - w1;
                    if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                        continue;
                    }
                    let z = w0 * pa.z + w1 * pb.z + w2 * pc.z;
                    let k = y * SIZE + x;
                    if z >= img.depth[k] {
                        continue;
                    }
                    let mut colour = base;
                    if let Some(tex) = &tex
                        && !mesh.uvs.is_empty()
                    {
                        let uv = mesh.uvs[a] * w0 + mesh.uvs[b] * w1 + mesh.uvs[c] * w2;
                        colour *= sample(tex, uv);
                    }
                    if !mesh.colors.is_empty() {
                        colour *= mesh.colors[a] * w0 + mesh.colors[b] * w1 + mesh.colors[c] * w2;
                    }
                    if let Some(cut) = cutoff
                        && colour.w < cut
                    {
                        continue;
                    }
                    let n = if mesh.normals.is_empty() {
                        Vec3::Y
                    } else {
                        (mesh.normals[a] * w0 + mesh.normals[b] * w1 + mesh.normals[c] * w2)
                            .normalize_or_zero()
                    };
                    let n = inst.transform.transform_vector3(n);
                    let light = 0.35
                        + 0.65
                            * n.dot(sun).abs().max(0.0)
                            * if mesh.material.double_sided {
                                1.0
                            } else {
                                n.dot(sun).signum().max(0.2)
                            };
                    img.depth[k] = z;
                    img.rgb[k] = (colour.truncate() * light).to_array();
                }
            }
        }
    }
    img
}

fn save(img: &Image, path: &Path) {
    let mut out = image::RgbImage::new(SIZE as u32, SIZE as u32);
    for (i, px) in img.rgb.iter().enumerate() {
        let s = |c: f32| (math::powf(c.clamp(0.0, 1.0), 1.0 / 2.2) * 255.0) as u8;
        out.put_pixel(
            (i % SIZE) as u32,
            (i / SIZE) as u32,
            image::Rgb([s(px[0]), s(px[1]), s(px[2])]),
        );
    }
    if let Err(e) = out.save(path) {
        eprintln!("{}: {e}", path.display());
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(out_dir) = args.next().map(PathBuf::from) else {
        eprintln!("usage: render_trees OUT_DIR SCRIPT...");
        std::process::exit(2);
    };
    let engine = match Engine::builder().plugin(SpaceColonizationPlugin).build() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    for script in args {
        let path = PathBuf::from(&script);
        let result = engine
            .session(SessionOptions::default())
            .and_then(|s| s.generate(&path, &mut |_, _| {}));
        match result {
            Ok(generated) => {
                let m = &generated.model;
                let stem = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                for (k, yaw) in [0.0f32, 1.6].iter().enumerate() {
                    save(&render(m, *yaw), &out_dir.join(format!("{stem}_{k}.png")));
                }
                let phases: Vec<String> = m
                    .stats
                    .phases
                    .iter()
                    .map(|(n, s)| format!("{n} {:.1} ms", s * 1e3))
                    .collect();
                println!(
                    "{script}: {} nodes, {} leaves, {} vertices, {} triangles, {:.0} ms ({})",
                    m.stats.nodes,
                    m.stats.leaves,
                    m.vertex_count(),
                    m.triangle_count(),
                    generated.seconds * 1e3,
                    phases.join(", ")
                );
            }
            Err(e) => eprintln!("{e}"),
        }
    }
}
