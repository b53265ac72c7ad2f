pub struct ObjFiles; pub fn obj_files(){}
