//! The binary chunk's buffer views and the accessors that read them: vertex attributes,
//! indices and per-instance floats, placed now and written when the file is.

use std::sync::Arc;

use gltf_json as json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use serde_json::{Value as JsonValue, json};

use super::*;
use crate::geometry::Mesh;

impl Builder {
    /// A buffer view of `data` at the next 4-byte boundary of the buffer, placed now and
    /// written when the file is (see [`Layout`]).
    pub(super) fn view(
        &mut self,
        data: Data,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        let (offset, len) = self.layout.place(data);
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64(len as u64),
            byte_offset: Some(USize64(offset as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: None,
        })
    }

    /// An accessor of the `count` elements of `data`, in a view of its own.
    pub(super) fn accessor(
        &mut self,
        data: Data,
        count: usize,
        component: json::accessor::ComponentType,
        type_: json::accessor::Type,
        bounds: Option<(JsonValue, JsonValue)>,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::Accessor> {
        let view = self.view(data, target);
        let (min, max) = match bounds {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: Some(USize64(0)),
            count: USize64(count as u64),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A VEC3 float vertex attribute of `mesh` (positions or normals), with its `min`/`max`
    /// when `bounds`.
    pub(super) fn vec3s(
        &mut self,
        mesh: &Arc<Mesh>,
        attribute: Attribute,
        bounds: bool,
    ) -> json::Index<json::Accessor> {
        let data = match attribute {
            Attribute::Normals => &mesh.normals,
            _ => &mesh.positions,
        };
        let b = bounds.then(|| {
            let (lo, hi) = vec3_bounds(data);
            (json!(lo.to_vec()), json!(hi.to_vec()))
        });
        self.accessor(
            Data::Mesh(mesh.clone(), attribute),
            data.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec3,
            b,
            Some(json::buffer::Target::ArrayBuffer),
        )
    }

    /// A VEC2 float vertex attribute (texture coordinates).
    pub(super) fn vec2s(&mut self, mesh: &Arc<Mesh>) -> json::Index<json::Accessor> {
        self.accessor(
            Data::Mesh(mesh.clone(), Attribute::Uvs),
            mesh.uvs.len(),
            json::accessor::ComponentType::F32,
            json::accessor::Type::Vec2,
            None,
            Some(json::buffer::Target::ArrayBuffer),
        )
    }

    /// A `COLOR_0` accessor: linear RGBA as normalized unsigned bytes (4 bytes a vertex
    /// instead of 16), rounded to the nearest of the 256 steps.
    pub(super) fn colors(&mut self, mesh: &Arc<Mesh>) -> json::Index<json::Accessor> {
        let index = self.accessor(
            Data::Mesh(mesh.clone(), Attribute::Colors),
            mesh.colors.len(),
            json::accessor::ComponentType::U8,
            json::accessor::Type::Vec4,
            None,
            Some(json::buffer::Target::ArrayBuffer),
        );
        if let Some(accessor) = self.root.accessors.get_mut(index.value()) {
            accessor.normalized = true;
        }
        index
    }

    /// A float accessor of per-instance data (no buffer view target: not a vertex attribute).
    pub(super) fn instance_floats(
        &mut self,
        data: Vec<f32>,
        per: usize,
    ) -> json::Index<json::Accessor> {
        use json::accessor::Type;
        let type_ = if per == 3 { Type::Vec3 } else { Type::Vec4 };
        let count = data.len() / per;
        self.accessor(
            Data::Floats(data),
            count,
            json::accessor::ComponentType::F32,
            type_,
            None,
            None,
        )
    }
}
