// partscene 3D view: primitives (instanced unit meshes), scan points (instanced screen-space
// quads) and lines (axes, limits, contact edges, floor grid). Colours come in sRGB; lighting is
// done in linear space and the result is written sRGB-encoded into an Rgba8Unorm target.

struct Frame {
    clip_from_world: mat4x4<f32>,
    eye_world: vec4<f32>,
    // x, y: viewport size in pixels; z: point size in pixels; w: unused.
    viewport: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(hi, lo, c <= vec3<f32>(0.04045));
}

fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

// ---- primitives -------------------------------------------------------------------------------

struct SolidOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal_world: vec3<f32>,
    @location(1) position_world: vec3<f32>,
    @location(2) color: vec4<f32>,
};

@vertex
fn vs_solid(
    @location(0) position_unit: vec3<f32>,
    @location(1) normal_unit: vec3<f32>,
    @location(2) m0: vec4<f32>,
    @location(3) m1: vec4<f32>,
    @location(4) m2: vec4<f32>,
    @location(5) m3: vec4<f32>,
    @location(6) n0: vec4<f32>,
    @location(7) n1: vec4<f32>,
    @location(8) n2: vec4<f32>,
    @location(9) color: vec4<f32>,
) -> SolidOut {
    let world_from_unit = mat4x4<f32>(m0, m1, m2, m3);
    let normal_from_unit = mat3x3<f32>(n0.xyz, n1.xyz, n2.xyz);
    let world = world_from_unit * vec4<f32>(position_unit, 1.0);
    var out: SolidOut;
    out.clip = frame.clip_from_world * world;
    out.normal_world = normalize(normal_from_unit * normal_unit);
    out.position_world = world.xyz;
    out.color = color;
    return out;
}

@fragment
fn fs_solid(in: SolidOut) -> @location(0) vec4<f32> {
    let to_eye = normalize(frame.eye_world.xyz - in.position_world);
    var n = normalize(in.normal_world);
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    // A head light plus a fixed key light from above, and ambient.
    let key = normalize(vec3<f32>(0.3, 0.5, 1.0));
    let diffuse = 0.35 * max(dot(n, to_eye), 0.0) + 0.5 * max(dot(n, key), 0.0) + 0.22;
    let base = srgb_to_linear(in.color.rgb);
    return vec4<f32>(linear_to_srgb(min(base * diffuse, vec3<f32>(1.0))), in.color.a);
}

// ---- points -----------------------------------------------------------------------------------

struct PointOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_point(@builtin(vertex_index) corner: u32, @location(0) position_world: vec3<f32>, @location(1) color: vec4<f32>) -> PointOut {
    var offsets = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    var out: PointOut;
    let clip = frame.clip_from_world * vec4<f32>(position_world, 1.0);
    let half_size_ndc = frame.viewport.z / frame.viewport.xy;
    out.clip = clip + vec4<f32>(offsets[corner] * half_size_ndc * clip.w, 0.0, 0.0);
    out.color = color;
    return out;
}

@fragment
fn fs_point(in: PointOut) -> @location(0) vec4<f32> {
    return in.color;
}

// ---- lines ------------------------------------------------------------------------------------

@vertex
fn vs_line(@location(0) position_world: vec3<f32>, @location(1) color: vec4<f32>) -> PointOut {
    var out: PointOut;
    out.clip = frame.clip_from_world * vec4<f32>(position_world, 1.0);
    out.color = color;
    return out;
}
