//! Writing models: glTF 2.0 binary (`.glb`) and Wavefront `.obj` + `.mtl`.

mod glb;
mod obj;

pub use glb::{ExportMeta, glb_bytes, glb_stages_bytes};
pub use obj::{ObjFiles, obj_files};
