// Terrain shading: flat (face normals) with a light hillshade, and a barycentric wireframe for culled groups.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // xyz: unit direction towards the light; w: unused.
    light: vec4<f32>,
    // x: ambient share of the hillshade; y: how far the wireframe colour is mixed towards white.
    params: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;

struct VsIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec4<f32>,
};

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) colour: vec4<f32>,
    @location(2) bary: vec3<f32>,
};

@vertex
fn vs_main(v: VsIn, @builtin(vertex_index) index: u32) -> VsOut {
    var out: VsOut;
    out.clip = u.view_proj * vec4<f32>(v.position, 1.0);
    out.normal = v.normal;
    out.colour = v.colour;
    // Vertices are unshared and the index buffer is the identity, so index % 3 is the corner.
    let corner = index % 3u;
    out.bary = vec3<f32>(f32(corner == 0u), f32(corner == 1u), f32(corner == 2u));
    return out;
}

fn shade(normal: vec3<f32>) -> f32 {
    let n = normalize(normal);
    let lambert = max(dot(n, u.light.xyz), 0.0);
    return u.params.x + (1.0 - u.params.x) * lambert;
}

@fragment
fn fs_solid(i: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(i.colour.rgb * shade(i.normal), 1.0);
}

@fragment
fn fs_wire(i: VsOut) -> @location(0) vec4<f32> {
    let width = max(fwidth(i.bary), vec3<f32>(1e-6));
    let edge = i.bary / width;
    if min(min(edge.x, edge.y), edge.z) > 1.0 {
        discard;
    }
    return vec4<f32>(mix(i.colour.rgb, vec3<f32>(1.0), u.params.y), 1.0);
}
