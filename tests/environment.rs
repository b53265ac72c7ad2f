//! End-to-end tests of environment maps: `model:setEnvironment(img)` in a script puts an
//! equirectangular sky image in the glb, named by the root `extras.pge.environment`.

mod common;

use common::{pge, pge_in, root};

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

#[test]
fn set_environment_writes_a_sky_image_named_by_the_extras() {
    assert!(root().join("tests/scripts/environment.lua").is_file());
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("environment.glb");
    let out_s = out.to_string_lossy().to_string();
    let o = pge(&[
        "run",
        "tests/scripts/environment.lua",
        "-o",
        out_s.as_str(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let glb = std::fs::read(&out).expect("glb written");
    let gltf = gltf::Gltf::from_slice(&glb).expect("valid glTF");
    let names: Vec<_> = gltf
        .meshes()
        .map(|m| m.name().map(str::to_string))
        .collect();
    assert_eq!(
        names.len(),
        2,
        "the model's mesh and the sky dome: {names:?}"
    );
    assert!(names.contains(&Some("sky".into())), "{names:?}");
    let extras: serde_json::Value = serde_json::from_str(
        gltf.document
            .as_json()
            .extras
            .as_ref()
            .expect("root extras")
            .get(),
    )
    .expect("json");
    let env = &extras["pge"]["environment"];
    assert_eq!(env["mapping"], "equirectangular", "{extras}");
    let index = env["image"].as_u64().expect("an image index") as usize;
    let image = gltf.images().nth(index).expect("the index names an image");
    let gltf::image::Source::View { view, mime_type } = image.source() else {
        panic!("the sky is embedded, not a uri");
    };
    assert_eq!(mime_type, "image/png");
    let blob = gltf.blob.as_ref().expect("binary chunk");
    let png = &blob[view.offset()..view.offset() + view.length()];
    let sky = image::load_from_memory(png)
        .expect("a decodable PNG")
        .to_rgba8();
    assert_eq!(sky.dimensions(), (64, 32), "2:1, as the script made it");
    // Row 0 is the zenith (blue), the bottom row the ground (brown).
    let top = sky.get_pixel(10, 0).0;
    let bottom = sky.get_pixel(10, 31).0;
    assert!(top[2] > 200 && top[2] > top[0] + 100, "zenith {top:?}");
    assert!(bottom[0] > bottom[2], "ground {bottom:?}");
    // Same seed, same bytes.
    let again = dir.path().join("again.glb");
    let again_s = again.to_string_lossy().to_string();
    let o = pge(&[
        "run",
        "tests/scripts/environment.lua",
        "-o",
        again_s.as_str(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(std::fs::read(&again).expect("glb") == glb);
}

#[test]
fn set_environment_accepts_a_png_path_and_locates_bad_arguments() {
    let dir = tempfile::tempdir().expect("tempdir");
    let sky = image::RgbaImage::from_pixel(8, 4, image::Rgba([30, 60, 200, 255]));
    sky.save(dir.path().join("sky.png")).expect("png");
    std::fs::write(
        dir.path().join("path.lua"),
        "local m = pge.model()\nm:add(pge.mesh{positions = {0,0,0, 1,0,0, 0,1,0}, indices = {0,1,2}})\nm:setEnvironment(\"sky.png\")\nreturn m\n",
    )
    .expect("write");
    let o = pge_in(&["run", "path.lua", "-o", "path.glb", "-q"], dir.path());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let gltf = gltf::Gltf::open(dir.path().join("path.glb")).expect("valid glTF");
    assert_eq!(gltf.images().count(), 1);

    std::fs::write(
        dir.path().join("bad.lua"),
        "local m = pge.model()\n\nm:setEnvironment(42)\nreturn m\n",
    )
    .expect("write");
    let o = pge_in(&["run", "bad.lua", "-o", "bad.glb", "-q"], dir.path());
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("bad.lua:3:"), "{err}");
    assert!(err.contains("setEnvironment"), "{err}");
    assert!(!err.contains("panicked"), "{err}");

    std::fs::write(
        dir.path().join("missing.lua"),
        "local m = pge.model()\nm:setEnvironment(\"nowhere.png\")\nreturn m\n",
    )
    .expect("write");
    let o = pge_in(
        &["run", "missing.lua", "-o", "missing.glb", "-q"],
        dir.path(),
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("missing.lua:2:"), "{err}");
}

#[test]
fn the_sky_example_writes_its_environment() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("sky.glb");
    let out_s = out.to_string_lossy().to_string();
    let o = pge(&[
        "run",
        "scripts/examples/sky.lua",
        "-o",
        out_s.as_str(),
        "-q",
        "--set",
        "width=64",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let gltf = gltf::Gltf::open(&out).expect("valid glTF");
    let extras: serde_json::Value = serde_json::from_str(
        gltf.document
            .as_json()
            .extras
            .as_ref()
            .expect("root extras")
            .get(),
    )
    .expect("json");
    let index = extras["pge"]["environment"]["image"]
        .as_u64()
        .expect("an environment image") as usize;
    assert!(gltf.images().nth(index).is_some());
    assert_eq!(gltf.nodes().count(), 10, "nine stones and the sky dome");
    let scene = gltf.default_scene().expect("a scene");
    let sky = scene
        .nodes()
        .find(|n| n.name() == Some("sky"))
        .expect("the sky dome in the scene");
    let texture = sky
        .mesh()
        .and_then(|m| m.primitives().next())
        .and_then(|p| p.material().pbr_metallic_roughness().base_color_texture())
        .expect("the dome is textured");
    assert_eq!(
        texture.texture().source().index(),
        index,
        "the dome shows the environment image"
    );
}
