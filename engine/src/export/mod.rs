//! Writing models: glTF 2.0 binary (`.glb`), Wavefront `.obj` + `.mtl`, and USD (`.usda`,
//! `.usdz`).

mod glb;
mod glb_container;
mod glb_extras;
mod glb_layout;
mod glb_sky;
mod obj;
mod usd;

pub use glb::shared::{
    SharedGroup, SharedVariants, VARIANTS_FORMAT, glb_bytes_shared, variants_files,
};
pub use glb::{
    ExportMeta, GLB_LIMIT, GPU_INSTANCING, GlbFile, Instancing, glb_bytes, glb_bytes_with,
    glb_container, glb_file_with, glb_stages_bytes, lod_from_json, write_glb_with,
};
pub use glb_extras::SkeletonText;
pub use obj::{ObjFiles, obj_files};
pub use usd::{USD_ROOT, UsdFiles, usd_files, usd_stages_files, usdz_bytes};
