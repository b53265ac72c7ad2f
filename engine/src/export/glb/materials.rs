//! Materials, their textures and the embedded images (each written once however many
//! meshes use it).

use std::sync::Arc;

use gltf_json as json;
use json::validation::Checked::Valid;

use super::*;
use crate::geometry::{AlphaMode, Material, Texture};

impl Builder {
    /// The embedded image of `tex` (PNG or JPEG), written once however many textures (and the
    /// environment) use it.
    pub(super) fn image(&mut self, tex: &Arc<Texture>) -> json::Index<json::Image> {
        if let Some(i) = written(&self.images, tex) {
            return i;
        }
        let view = self.view(Data::Image(tex.clone()), None);
        let index = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType(tex.mime_type().into())),
            name: Some(tex.name.clone()),
            uri: None,
            extensions: None,
            extras: None,
        });
        self.images.push((tex.clone(), index));
        index
    }

    pub(super) fn texture(&mut self, tex: &Arc<Texture>) -> json::Index<json::Texture> {
        if let Some(i) = written(&self.textures, tex) {
            return i;
        }
        let image = self.image(tex);
        let sampler = *self.sampler.get_or_insert_with(|| {
            self.root.push(json::texture::Sampler {
                mag_filter: Some(Valid(json::texture::MagFilter::Linear)),
                min_filter: Some(Valid(json::texture::MinFilter::LinearMipmapLinear)),
                wrap_s: Valid(json::texture::WrappingMode::Repeat),
                wrap_t: Valid(json::texture::WrappingMode::Repeat),
                ..Default::default()
            })
        });
        let index = self.root.push(json::Texture {
            name: Some(tex.name.clone()),
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: None,
        });
        self.textures.push((tex.clone(), index));
        index
    }

    pub(super) fn material(&mut self, m: &Arc<Material>) -> json::Index<json::Material> {
        if let Some(i) = written(&self.materials, m) {
            return i;
        }
        let base_color_texture = m.texture.as_ref().map(|t| json::texture::Info {
            index: self.texture(t),
            tex_coord: 0,
            extensions: None,
            extras: None,
        });
        let normal_texture = m
            .normal_texture
            .as_ref()
            .map(|t| json::material::NormalTexture {
                index: self.texture(t),
                scale: 1.0,
                tex_coord: 0,
                extensions: None,
                extras: None,
            });
        let metallic_roughness_texture =
            m.metallic_roughness_texture
                .as_ref()
                .map(|t| json::texture::Info {
                    index: self.texture(t),
                    tex_coord: 0,
                    extensions: None,
                    extras: None,
                });
        let (alpha_mode, alpha_cutoff) = match m.alpha {
            AlphaMode::Opaque => (json::material::AlphaMode::Opaque, None),
            AlphaMode::Mask(c) => (
                json::material::AlphaMode::Mask,
                Some(json::material::AlphaCutoff(c)),
            ),
            AlphaMode::Blend => (json::material::AlphaMode::Blend, None),
        };
        let index = self.root.push(json::Material {
            name: Some(m.name.clone()),
            alpha_mode: Valid(alpha_mode),
            alpha_cutoff,
            double_sided: m.double_sided,
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(m.base_color),
                base_color_texture,
                metallic_factor: json::material::StrengthFactor(m.metallic),
                roughness_factor: json::material::StrengthFactor(m.roughness),
                metallic_roughness_texture,
                ..Default::default()
            },
            normal_texture,
            ..Default::default()
        });
        if let Some(t) = m.transmission {
            self.transmissive.push((index.value(), t));
        }
        self.materials.push((m.clone(), index));
        index
    }
}
