// The preview's shaders: lit instanced meshes, unlit lines, the environment's sky. Colours are linear until the
// fragment output, which is sRGB-encoded; overlay line colours are given encoded.

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: direction towards the sun.
    sun: vec4<f32>,
    // The inverse of view_proj: clip space back to world space (the sky's view rays).
    inv_view_proj: mat4x4<f32>,
    // xyz: factor of the ambient light (white without an environment, tinted by the sky's
    // average colour with one).
    ambient: vec4<f32>,
};
@group(0) @binding(0) var<uniform> g: Globals;

struct Material {
    base_color: vec4<f32>,
    // x: alpha cutoff (negative: none), y: 1 when double-sided.
    params: vec4<f32>,
    // Light through the surface (leaves' diffuse transmission): rgb the tint of back faces
    // and of the light passing through, w the share of the sun behind a face that shines
    // through it. White and 0 for opaque surfaces.
    back: vec4<f32>,
};
@group(1) @binding(0) var<uniform> m: Material;
@group(1) @binding(1) var base_tex: texture_2d<f32>;
@group(1) @binding(2) var base_sampler: sampler;
// Tangent-space normal map (+Z out of the surface); a flat texel without one.
@group(1) @binding(3) var normal_tex: texture_2d<f32>;

struct MeshIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) color: vec4<f32>,
    @location(4) m0: vec4<f32>,
    @location(5) m1: vec4<f32>,
    @location(6) m2: vec4<f32>,
    @location(7) m3: vec4<f32>,
    // The glb's TANGENT where a normal map reads it; zero elsewhere.
    @location(8) tangent: vec4<f32>,
};

struct MeshOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) uv: vec2<f32>,
    @location(2) color: vec4<f32>,
    @location(3) tangent: vec4<f32>,
};

@vertex
fn vs_mesh(v: MeshIn) -> MeshOut {
    let model = mat4x4<f32>(v.m0, v.m1, v.m2, v.m3);
    var out: MeshOut;
    out.clip = g.view_proj * (model * vec4<f32>(v.position, 1.0));
    out.normal = (model * vec4<f32>(v.normal, 0.0)).xyz;
    out.uv = v.uv;
    out.color = v.color;
    out.tangent = vec4<f32>((model * vec4<f32>(v.tangent.xyz, 0.0)).xyz, v.tangent.w);
    return out;
}

@fragment
fn fs_mesh(in: MeshOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    let c = m.base_color * in.color * textureSample(base_tex, base_sampler, in.uv);
    // Sampled here, in uniform control flow (a flat texel without a normal map).
    let mapped = textureSample(normal_tex, base_sampler, in.uv).xyz * 2.0 - 1.0;
    // The alpha test of glTF clients: the material's cutoff against the box-filtered mip
    // chain, which a leaf texture's mean alpha keeps above the cutoff (docs/glb.md).
    if m.params.x >= 0.0 && c.a < m.params.x {
        discard;
    }
    var n = normalize(in.normal);
    // The normal map in the tangent frame the glb carries (bitangent = cross(N, T) * w),
    // as glTF clients read it.
    if dot(in.tangent.xyz, in.tangent.xyz) > 1e-12 {
        let t = normalize(in.tangent.xyz - n * dot(n, in.tangent.xyz));
        let b = cross(n, t) * select(1.0, -1.0, in.tangent.w < 0.0);
        n = normalize(t * mapped.x + b * mapped.y + n * mapped.z);
    }
    if !front {
        n = -n;
    }
    let sun = max(dot(n, g.sun.xyz), 0.0);
    // The sun behind the face, seen through it (translucent leaves).
    let behind = max(-dot(n, g.sun.xyz), 0.0) * m.back.w;
    // Hemisphere ambient: warm ground below, cool sky above.
    let ambient = mix(vec3<f32>(0.16, 0.14, 0.12), vec3<f32>(0.38, 0.42, 0.50), n.y * 0.5 + 0.5)
        * g.ambient.xyz;
    let sun_color = vec3<f32>(1.0, 0.95, 0.85);
    let light = ambient + sun_color * (sun * 0.85 + behind * 0.85 * m.back.rgb);
    // A back face (a leaf's underside) in its own tint.
    let tint = select(m.back.rgb, vec3<f32>(1.0), front);
    return vec4<f32>(srgb(c.rgb * tint * light), 1.0);
}

// Linear to sRGB encoding (the viewport texture is read by egui as encoded colour).
fn srgb(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, x * 12.92, x <= vec3<f32>(0.0031308));
}

@fragment
fn fs_mesh_lines(in: MeshOut) -> @location(0) vec4<f32> {
    let c = m.base_color * in.color;
    return vec4<f32>(srgb(c.rgb), 1.0);
}

// The environment: one triangle covering the viewport, drawn first and without depth, so
// every mesh and line lands in front of it. Each pixel looks up the equirectangular sky
// (bound as a material texture) in the direction its view ray goes.
struct SkyOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) ndc: vec2<f32>,
};

@vertex
fn vs_sky(@builtin(vertex_index) i: u32) -> SkyOut {
    var corners = array<vec2<f32>, 3>(vec2<f32>(-1.0, -1.0), vec2<f32>(3.0, -1.0), vec2<f32>(-1.0, 3.0));
    var out: SkyOut;
    out.clip = vec4<f32>(corners[i], 1.0, 1.0);
    out.ndc = corners[i];
    return out;
}

const PI: f32 = 3.14159265;

@fragment
fn fs_sky(in: SkyOut) -> @location(0) vec4<f32> {
    let a = g.inv_view_proj * vec4<f32>(in.ndc, 0.0, 1.0);
    let b = g.inv_view_proj * vec4<f32>(in.ndc, 0.5, 1.0);
    let d = normalize(b.xyz / b.w - a.xyz / a.w);
    // Row 0 straight up, the middle row the horizon; the middle column looks along -Z,
    // a quarter further along +X.
    let u = 0.5 + atan2(d.x, -d.z) / (2.0 * PI);
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    // Level 0 only: the seam where u wraps would otherwise pick the smallest mip level.
    let c = textureSampleLevel(base_tex, base_sampler, vec2<f32>(u, v), 0.0);
    return vec4<f32>(srgb(c.rgb), 1.0);
}

struct LineIn {
    @location(0) position: vec3<f32>,
    @location(1) color: vec4<f32>,
};

struct LineOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_line(v: LineIn) -> LineOut {
    var out: LineOut;
    out.clip = g.view_proj * vec4<f32>(v.position, 1.0);
    out.color = v.color;
    return out;
}

@fragment
fn fs_line(in: LineOut) -> @location(0) vec4<f32> {
    return in.color;
}

// Probe: one triangle, counter-clockwise in normalized device coordinates, covering the
// target; white where the rasterizer calls it front-facing. Tells whether this backend
// needs the front face declared clockwise.
@vertex
fn vs_probe(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    var corners = array<vec2<f32>, 3>(vec2<f32>(-1.0, -1.0), vec2<f32>(3.0, -1.0), vec2<f32>(-1.0, 3.0));
    return vec4<f32>(corners[i], 0.5, 1.0);
}

@fragment
fn fs_probe(@builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    if front {
        return vec4<f32>(1.0, 1.0, 1.0, 1.0);
    }
    return vec4<f32>(0.0, 0.0, 0.0, 1.0);
}
