pub struct ExportMeta; pub fn glb_bytes(){}
