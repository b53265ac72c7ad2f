//! Writing models: glTF 2.0 binary (`.glb`), Wavefront `.obj` + `.mtl`, and USD (`.usda`,
//! `.usdz`).

mod glb;
mod obj;
mod usd;

use crate::{Location, Result, RunContext};

/// The deadline an export keeps to: the run's ([`RunContext::check_deadline`]), its error
/// placed at `at` (the line that returned what is exported). The default never stops.
#[derive(Clone, Debug, Default)]
pub struct ExportLimit {
    /// The run's deadline and stop flags.
    pub ctx: RunContext,
    /// Where a limit error points.
    pub at: Location,
}

impl ExportLimit {
    /// The typed [`crate::Error::TimeLimit`] (or cancellation) once the run must stop.
    pub fn check(&self) -> Result<()> {
        self.ctx.check_deadline(&self.at)
    }
}

pub use glb::shared::{
    SharedGroup, SharedVariants, VARIANTS_FORMAT, glb_bytes_shared, variants_files,
};
pub use glb::{
    ExportMeta, GLB_LIMIT, GPU_INSTANCING, GlbFile, Instancing, Prepared, glb_bytes,
    glb_bytes_with, glb_container, glb_file_with, glb_stages_bytes, lod_from_json,
    write_glb_checked, write_glb_with,
};
pub use obj::{ObjFiles, obj_files, obj_files_checked};
pub use usd::{USD_ROOT, UsdFiles, usd_files, usd_stages_files, usdz_bytes};
