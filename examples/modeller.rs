//! Runs a modeller script with the extruder, metaballs, canvas and L-system plugins, writes the `.glb`
//! and a shaded software render (`.png`) of it, to look at a script's output without a
//! window:
//!
//! ```text
//! cargo run --example modeller -- scripts/modellers/tower.lua /tmp/tower [--set k=v] [--steps n]
//! ```

use pge_engine::math;
use std::collections::HashMap;
use std::error::Error;
use std::path::PathBuf;

use glam::{Mat4, Vec2, Vec3, Vec4};
use pge_engine::geometry::{Model, Primitive};
use pge_engine::{Engine, SessionOptions};

const SIZE: usize = 640;

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let script = PathBuf::from(
        args.next()
            .ok_or("usage: modeller SCRIPT OUT_STEM [--set k=v] [--steps n]")?,
    );
    let out = PathBuf::from(args.next().ok_or("missing OUT_STEM")?);
    let mut options = SessionOptions::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--set" => {
                let kv = args.next().ok_or("--set needs NAME=VALUE")?;
                let (k, v) = kv.split_once('=').ok_or("--set needs NAME=VALUE")?;
                options.params.push((k.into(), v.into()));
            }
            "--steps" => options.steps = Some(args.next().ok_or("--steps needs N")?.parse()?),
            "--seed" => options.seed = args.next().ok_or("--seed needs N")?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let engine = Engine::builder()
        .plugin(pge_extruder::ExtruderPlugin)
        .plugin(pge_metaballs::MetaballsPlugin)
        .plugin(pge_canvas::CanvasPlugin)
        .plugin(pge_lsystem::LSystemPlugin)
        .build()?;
    let session = engine.session(options)?;
    let generated = session.generate(&script, &mut |_, _| {})?;
    let model = generated.model;
    model.validate()?;
    let glb = pge_engine::export::glb_bytes(&model, &Default::default())?;
    std::fs::write(out.with_extension("glb"), glb)?;
    let lines: usize = model
        .instances
        .iter()
        .filter(|i| model.meshes[i.mesh].primitive == Primitive::Lines)
        .map(|i| model.meshes[i.mesh].indices.len() / 2)
        .sum();
    let bounds = model.bounds();
    println!(
        "{}: {} meshes, {} instances, {} vertices, {} triangles, {} line segments, {} modules, bounds {:?}",
        script.display(),
        model.meshes.len(),
        model.instances.len(),
        model.vertex_count(),
        model.triangle_count(),
        lines,
        model.stats.modules,
        bounds
    );
    render(&model).save(out.with_extension("png"))?;
    Ok(())
}

/// A z-buffered, Lambert-shaded orthographic view from above-front-right.
fn render(model: &Model) -> image::RgbImage {
    let mut img = image::RgbImage::from_pixel(SIZE as u32, SIZE as u32, image::Rgb([40, 44, 52]));
    let Some((lo, hi)) = model.bounds() else {
        return img;
    };
    let center = (lo + hi) * 0.5;
    let eye_dir = Vec3::new(1.0, 0.9, 1.4).normalize();
    let view = Mat4::look_at_rh(center + eye_dir, center, Vec3::Y);
    // Fit the projected bounds.
    let mut pmin = Vec2::splat(f32::MAX);
    let mut pmax = Vec2::splat(f32::MIN);
    for inst in &model.instances {
        for p in &model.meshes[inst.mesh].positions {
            let v = view.transform_point3(inst.transform.transform_point3(*p));
            pmin = pmin.min(v.truncate());
            pmax = pmax.max(v.truncate());
        }
    }
    let scale = (SIZE as f32 * 0.92) / (pmax - pmin).max_element().max(1e-6);
    let mid = (pmin + pmax) * 0.5;
    let to_screen = |v: Vec3| {
        Vec3::new(
            (v.x - mid.x) * scale + SIZE as f32 / 2.0,
            SIZE as f32 / 2.0 - (v.y - mid.y) * scale,
            v.z,
        )
    };
    let light = Vec3::new(0.4, 1.0, 0.6).normalize();
    let mut depth = vec![f32::MIN; SIZE * SIZE];
    let mut textures: HashMap<usize, image::RgbaImage> = HashMap::new();
    for inst in &model.instances {
        let mesh = &model.meshes[inst.mesh];
        let tex = mesh.material.texture.as_ref().and_then(|t| {
            textures.entry(inst.mesh).or_insert_with(|| {
                image::load_from_memory(&t.encoded)
                    .map(|i| i.to_rgba8())
                    .unwrap_or_default()
            });
            textures.get(&inst.mesh).cloned()
        });
        let base = Vec4::from(mesh.material.base_color);
        let world: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| inst.transform.transform_point3(*p))
            .collect();
        let screen: Vec<Vec3> = world
            .iter()
            .map(|p| to_screen(view.transform_point3(*p)))
            .collect();
        let color_of = |i: usize, uv: Option<Vec2>| {
            let mut c = base * mesh.colors.get(i).copied().unwrap_or(Vec4::ONE);
            if let (Some(t), Some(uv)) = (&tex, uv) {
                let x = ((uv.x.clamp(0.0, 0.9999)) * t.width() as f32) as u32;
                let y = ((uv.y.clamp(0.0, 0.9999)) * t.height() as f32) as u32;
                let px = t.get_pixel(x, y).0;
                c *= Vec4::new(lin(px[0]), lin(px[1]), lin(px[2]), 1.0);
            }
            c
        };
        match mesh.primitive {
            Primitive::Triangles => {
                for t in mesh.indices.chunks_exact(3) {
                    let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
                    let n = (world[b] - world[a])
                        .cross(world[c] - world[a])
                        .normalize_or_zero();
                    let shade = 0.25 + 0.75 * n.dot(light).abs();
                    let (sa, sb, sc) = (screen[a], screen[b], screen[c]);
                    let area = (sb - sa).truncate().perp_dot((sc - sa).truncate());
                    if area.abs() < 1e-9 {
                        continue;
                    }
                    let x0 = sa.x.min(sb.x).min(sc.x).floor().max(0.0) as usize;
                    let x1 = (sa.x.max(sb.x).max(sc.x).ceil() as usize).min(SIZE - 1);
                    let y0 = sa.y.min(sb.y).min(sc.y).floor().max(0.0) as usize;
                    let y1 = (sa.y.max(sb.y).max(sc.y).ceil() as usize).min(SIZE - 1);
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                            let w0 = (sc - sb).truncate().perp_dot(p - sb.truncate()) / area;
                            let w1 = (sa - sc).truncate().perp_dot(p - sc.truncate()) / area;
                            let w2 = 1.0 - w0 - w1;
                            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                                continue;
                            }
                            let z = w0 * sa.z + w1 * sb.z + w2 * sc.z;
                            let k = y * SIZE + x;
                            if z <= depth[k] {
                                continue;
                            }
                            depth[k] = z;
                            let uv = (!mesh.uvs.is_empty())
                                .then(|| mesh.uvs[a] * w0 + mesh.uvs[b] * w1 + mesh.uvs[c] * w2);
                            let col =
                                color_of(a, uv) * w0 + color_of(b, uv) * w1 + color_of(c, uv) * w2;
                            img.put_pixel(x as u32, y as u32, pixel(col.truncate() * shade));
                        }
                    }
                }
            }
            Primitive::Lines => {
                for l in mesh.indices.chunks_exact(2) {
                    let (a, b) = (screen[l[0] as usize], screen[l[1] as usize]);
                    let col = color_of(l[0] as usize, None).truncate();
                    let steps = (b - a).truncate().length().ceil().max(1.0) as usize;
                    for s in 0..=steps {
                        let p = a.lerp(b, s as f32 / steps as f32);
                        let (x, y) = (p.x as isize, p.y as isize);
                        if x < 0 || y < 0 || x >= SIZE as isize || y >= SIZE as isize {
                            continue;
                        }
                        let k = y as usize * SIZE + x as usize;
                        if p.z + 1e-3 >= depth[k] {
                            depth[k] = p.z;
                            img.put_pixel(x as u32, y as u32, pixel(col));
                        }
                    }
                }
            }
        }
    }
    img
}

fn lin(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        math::powf((c + 0.055) / 1.055, 2.4)
    }
}

fn pixel(linear: Vec3) -> image::Rgb<u8> {
    let s = |c: f32| {
        let c = c.clamp(0.0, 1.0);
        let v = if c <= 0.003_130_8 {
            c * 12.92
        } else {
            1.055 * math::powf(c, 1.0 / 2.4) - 0.055
        };
        (v * 255.0).round() as u8
    };
    image::Rgb([s(linear.x), s(linear.y), s(linear.z)])
}
