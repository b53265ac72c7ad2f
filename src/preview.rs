//! `pge preview`: the window of the `pge-preview` crate, with every plugin of the `pge`
//! command, the common script arguments and `pge run`'s writer for its export button.

use std::path::{Path, PathBuf};

use pge_engine::ParamInfo;
use pge_engine::export::{Instancing, Prepared};
use pge_engine::geometry::Model;
use pge_preview::{CameraSpec, PreviewOptions};

use crate::common::ScriptArgs;
use crate::output::{export_meta, write_model};

/// Arguments of `pge preview`.
#[derive(clap::Args, Clone, Debug)]
pub struct PreviewArgs {
    #[command(flatten)]
    pub script: ScriptArgs,
    /// Draws trees with levels of detail (`lod`) at this fraction of their leaves, 0.01 to 1.
    #[arg(long, value_name = "FRACTION", default_value_t = 1.0, value_parser = pge_preview::args::parse_fraction)]
    pub lod_level: f64,
    /// A forest's leaf budget: the most leaves its trees draw in a frame at rest, nearer
    /// trees finer (as many triangles again go to bark and other meshes).
    #[arg(long, value_name = "N", default_value_t = pge_preview::forest::DEFAULT_LEAF_BUDGET, value_parser = pge_preview::args::parse_budget)]
    pub leaf_budget: u64,
    /// Writes the first complete frame to this PNG file and exits.
    #[arg(long, value_name = "PNG")]
    pub screenshot: Option<PathBuf>,
    /// Places the camera instead of framing the model: `D` metres from the target
    /// horizontally, the eye at height `H`, looking at `TX,TY,TZ` (default: the centre of the
    /// model's bounds).
    #[arg(long, value_name = "D,H[,TX,TY,TZ]", value_parser = pge_preview::args::parse_camera, allow_hyphen_values = true)]
    pub camera: Option<CameraSpec>,
    /// Measures the viewport: once the first model is on screen, turns the camera once
    /// around it in N frames drawn as while dragging, then rests; prints where each frame's
    /// time went to stderr and closes (after `--screenshot`, if given, of the resting frame).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub orbit_frames: Option<u32>,
}

/// Writes the preview's model as `pge run` does.
fn export(model: &Model, seed: u64, params: &[ParamInfo], path: &Path) -> anyhow::Result<()> {
    let meta = export_meta(seed, params);
    write_model(
        model,
        &Prepared::default(),
        &meta,
        path,
        Instancing::Gpu,
        &pge_engine::export::ExportLimit::default(),
    )
}

/// Opens the preview window for `args`.
pub fn preview(args: &PreviewArgs) -> anyhow::Result<()> {
    let engine = args.script.limits(pge::default_engine()).build()?;
    let options = PreviewOptions {
        script: args.script.script.clone(),
        seed: args.script.seed,
        params: args.script.set.clone(),
        lod_level: args.lod_level,
        leaf_budget: args.leaf_budget,
        screenshot: args.screenshot.clone(),
        camera: args.camera,
        orbit_frames: args.orbit_frames,
        export: Some(export),
    };
    pge_preview::preview(engine, options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use pge_engine::geometry::Mesh;

    #[test]
    fn the_export_writes_glb_and_obj_as_pge_run_does() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
        let model = Model::from_mesh(mesh);
        let glb = dir.path().join("tree.glb");
        export(&model, 7, &[], &glb).expect("glb");
        assert_eq!(&std::fs::read(&glb).expect("written")[0..4], b"glTF");
        let obj = dir.path().join("tree.obj");
        export(&model, 7, &[], &obj).expect("obj");
        let text = std::fs::read_to_string(&obj).expect("written");
        assert!(text.contains("mtllib tree.mtl"), "{text}");
        assert!(dir.path().join("tree.mtl").is_file());
        assert!(export(&model, 7, &[], &dir.path().join("missing/tree.glb")).is_err());
    }
}
