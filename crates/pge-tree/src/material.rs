//! The tree's two materials: bark and leaves, procedural (from the process's texture
//! cache) or from an image.

use std::sync::Arc;

use pge_engine::geometry::{AlphaMode, DiffuseTransmission, Material};

use crate::{
    BarkParams, LeafOptions, LeafParams, MeshOptions, TextureSource, TreeError, bark_textures,
    leaf_textures, load_png,
};

/// The bark material: the procedural PBR set of the options' style, colour and size (base
/// colour, normal and roughness maps, from the process's [`TextureCache`]), or a file's
/// image as the base colour alone.
pub fn bark_material(options: &MeshOptions) -> Result<Arc<Material>, TreeError> {
    let mut material = Material {
        name: "bark".into(),
        base_color: [1.0; 4],
        roughness: 1.0,
        ..Material::default()
    };
    match &options.texture {
        TextureSource::Procedural => {
            let set = bark_textures(&BarkParams {
                style: options.bark,
                color: options.color,
                size: options.texture_size,
                depth: options.bark_depth,
                format: options.texture_format,
            })?;
            material.texture = Some(set.color.clone());
            material.normal_texture = Some(set.normal.clone());
            material.metallic_roughness_texture = Some(set.roughness.clone());
        }
        TextureSource::Image(t) => material.texture = Some(t.clone()),
        TextureSource::File(path) => material.texture = Some(load_png(path, "bark")?),
    }
    if material.metallic_roughness_texture.is_none() {
        material.roughness = 0.95;
    }
    Ok(Arc::new(material))
}

/// The leaf material: the procedural PBR set of the options' shape and card (alpha-masked
/// colour, normal and roughness maps) or a file's image, double-sided, letting light
/// through to its back face ([`leaf_transmission`]). The alpha cutoff is chosen with the
/// colour map so that a client's own mipmaps keep the cards ([`pge_lod::mask`]): a
/// procedural set's own, or an image's from its alpha (the image re-encoded with its colour
/// dilated under its clear texels, and its silhouettes thickened when it is too sparse for
/// any cutoff: see [`leaf_material_with_warning`]).
pub fn leaf_material(options: &LeafOptions) -> Result<Arc<Material>, TreeError> {
    leaf_material_with_warning(options).map(|(material, _)| material)
}

/// [`leaf_material`] and, when an image's silhouettes had to be thickened, a warning that
/// says so (`SOURCE: warning: leaves.texture: ...`).
pub fn leaf_material_with_warning(
    options: &LeafOptions,
) -> Result<(Arc<Material>, Option<String>), TreeError> {
    let mut material = Material {
        name: "leaves".into(),
        base_color: [1.0; 4],
        alpha: AlphaMode::Mask(0.5),
        double_sided: true,
        roughness: 1.0,
        ..Material::default()
    };
    let image = match &options.texture {
        TextureSource::Procedural => {
            let set = leaf_textures(&LeafParams {
                shape: options.shape,
                size: options.texture_size,
                per_card: options.per_card,
            })?;
            material.texture = Some(set.color.clone());
            material.normal_texture = Some(set.normal.clone());
            material.metallic_roughness_texture = Some(set.roughness.clone());
            material.alpha = AlphaMode::Mask(set.alpha_cutoff.unwrap_or(0.5));
            None
        }
        TextureSource::Image(t) => Some(t.clone()),
        TextureSource::File(path) => Some(load_png(path, "leaf")?),
    };
    let mut warning = None;
    if let Some(image) = image {
        let masked = pge_lod::mask::mask_texture(&image)?;
        if let Some(was) = masked.widened_from {
            let at = if options.source.is_empty() {
                String::new()
            } else {
                format!("{}: ", options.source)
            };
            warning = Some(format!(
                "{at}warning: leaves.texture: '{}' has mean alpha {was:.3}, too little for any \
                 alpha cutoff to keep it in a client's mipmaps (at least {:.2}); its \
                 silhouettes were thickened to mean alpha {:.3}",
                image.name,
                pge_lod::mask::CUTOFFS[pge_lod::mask::CUTOFFS.len() - 1] + pge_lod::mask::MARGIN,
                masked.mean_alpha
            ));
        }
        material.alpha = AlphaMode::Mask(masked.cutoff);
        material.texture = Some(Arc::new(masked.texture));
        material.roughness = 0.8;
    }
    material.transmission = leaf_transmission(options);
    Ok((Arc::new(material), warning))
}

/// The light a leaf lets through: `translucency` of it, in the leaves' back colour (glTF
/// `KHR_materials_diffuse_transmission`); none at translucency 0.
pub fn leaf_transmission(options: &LeafOptions) -> Option<DiffuseTransmission> {
    let [r, g, b, _] = options.back_color;
    (options.translucency > 0.0).then_some(DiffuseTransmission {
        factor: options.translucency.clamp(0.0, 1.0),
        color: [r, g, b],
    })
}
