//! Textures and samplers of the viewport: model images with their mipmaps, the white
//! stand-in for untextured materials, the samplers of materials and of the sky.

use eframe::egui_wgpu::wgpu;

use super::scene::TextureData;

/// Model textures are sRGB images, decoded to linear when sampled for lighting.
const IMAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Normal maps hold data, read as stored.
const DATA_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The samplers and the default texture every material may use.
pub struct Samplers {
    /// Base colour textures: repeating, trilinear.
    pub material: wgpu::Sampler,
    /// The sky: wraps around the horizon, clamps at the poles.
    pub sky: wgpu::Sampler,
    /// One white texel, for materials without a texture.
    pub white: wgpu::TextureView,
    /// One flat normal (+Z in tangent space), for materials without a normal map.
    pub flat_normal: wgpu::TextureView,
}

impl Samplers {
    /// Creates the samplers and uploads the white texel.
    #[must_use]
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Samplers {
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("base colour"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let sky_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sky"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let white_data = TextureData {
            width: 1,
            height: 1,
            levels: vec![vec![255; 4]],
        };
        let white = upload_texture(device, queue, &white_data);
        let flat_data = TextureData {
            width: 1,
            height: 1,
            levels: vec![vec![128, 128, 255, 255]],
        };
        let flat_normal = upload_data_texture(device, queue, &flat_data);
        Samplers {
            material: sampler,
            sky: sky_sampler,
            white,
            flat_normal,
        }
    }
}

/// Uploads an image with its mip levels; returns its view.
#[must_use]
pub fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    data: &TextureData,
) -> wgpu::TextureView {
    upload(device, queue, data, IMAGE_FORMAT)
}

/// Uploads a data texture (a normal map) with its mip levels, read as stored; returns its
/// view.
#[must_use]
pub fn upload_data_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    data: &TextureData,
) -> wgpu::TextureView {
    upload(device, queue, data, DATA_FORMAT)
}

fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    data: &TextureData,
    format: wgpu::TextureFormat,
) -> wgpu::TextureView {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("model texture"),
        size: wgpu::Extent3d {
            width: data.width,
            height: data.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: data.levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let (mut w, mut h) = (data.width, data.height);
    for (level, pixels) in data.levels.iter().enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            pixels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        (w, h) = ((w / 2).max(1), (h / 2).max(1));
    }
    texture.create_view(&Default::default())
}
