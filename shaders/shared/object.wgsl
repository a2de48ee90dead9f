// object.wgsl: signed distance functions of the seven built-in test solids.
//
// Twin of src/object/solids.rs: every constant OBJ_X here is `dims::X` there, and every
// obj_* function mirrors the Rust function of the same name (without the prefix). Change
// both together; tests/objects_wgsl.rs checks that the constants agree and that this file
// validates with naga.
//
// Object frame: the contact top is at the origin, the body lies in z <= 0, the finger comes
// from +z. Distances in mm, negative inside. Ids: see OBJ_SOLID_* (Solid::id in Rust).
// No bindings: this file is concatenated in front of stage shaders.
//
// Baked mesh grids (SdfGrid in src/object/sdf_grid.rs) are sampled by the renderer's own
// code: value index = x + dims.x * (y + dims.y * z), voxel centre = origin + voxel * (x,y,z).

const OBJ_SOLID_CONE: u32 = 0u;
const OBJ_SOLID_SPHERE: u32 = 1u;
const OBJ_SOLID_IRREGULAR_PRISM: u32 = 2u;
const OBJ_SOLID_CYLINDER: u32 = 3u;
const OBJ_SOLID_EDGE: u32 = 4u;
const OBJ_SOLID_TUBE: u32 = 5u;
const OBJ_SOLID_SLAB: u32 = 6u;
const OBJ_SOLID_TORUS: u32 = 7u;
const OBJ_SOLID_DISC: u32 = 8u;

// Dimensions (mm). Twin: `pub mod dims` in src/object/solids.rs.
const OBJ_CONE_RADIUS: f32 = 5.0;
const OBJ_CONE_HEIGHT: f32 = 10.0;
const OBJ_SPHERE_RADIUS: f32 = 5.0;
const OBJ_PRISM_HEIGHT: f32 = 10.0;
const OBJ_PRISM_PENTAGON: array<vec2<f32>, 5> = array<vec2<f32>, 5>(
    vec2<f32>(3.5, 0.5),
    vec2<f32>(1.0, 3.25),
    vec2<f32>(-2.875, 2.5),
    vec2<f32>(-3.5, -1.5),
    vec2<f32>(0.625, -3.25),
);
const OBJ_CYLINDER_RADIUS: f32 = 2.0;
const OBJ_CYLINDER_HEIGHT: f32 = 10.0;
const OBJ_EDGE_LENGTH: f32 = 10.0;
const OBJ_EDGE_WIDTH: f32 = 6.0;
const OBJ_EDGE_HEIGHT: f32 = 5.0;
const OBJ_TUBE_OUTER_RADIUS: f32 = 3.0;
const OBJ_TUBE_INNER_RADIUS: f32 = 2.0;
const OBJ_TUBE_HEIGHT: f32 = 10.0;
const OBJ_SLAB_X: f32 = 10.0;
const OBJ_SLAB_Y: f32 = 6.0;
const OBJ_SLAB_Z: f32 = 3.0;
const OBJ_TORUS_MAJOR_RADIUS: f32 = 4.0;
const OBJ_TORUS_MINOR_RADIUS: f32 = 1.0;
const OBJ_DISC_RADIUS: f32 = 5.0;
const OBJ_DISC_THICKNESS: f32 = 1.0;

// What solid_sdf returns for an unknown id: far away, so nothing touches.
const OBJ_FAR: f32 = 1.0e30;

// Exact SDF of an axis-aligned 2D box with centre c and half-extents h.
fn obj_sd_box2(p: vec2<f32>, c: vec2<f32>, h: vec2<f32>) -> f32 {
    let d = abs(p - c) - h;
    return length(max(d, vec2<f32>(0.0))) + min(max(d.x, d.y), 0.0);
}

// Exact SDF of an axis-aligned box with centre c and half-extents h.
fn obj_sd_box3(p: vec3<f32>, c: vec3<f32>, h: vec3<f32>) -> f32 {
    let d = abs(p - c) - h;
    return length(max(d, vec3<f32>(0.0))) + min(max(d.x, max(d.y, d.z)), 0.0);
}

// Exact SDF of a simple polygon given by its first n corners (n <= 5), either winding:
// distance to the nearest edge, signed by crossing parity (after Inigo Quilez).
fn obj_sd_polygon(corners: array<vec2<f32>, 5>, n: u32, p: vec2<f32>) -> f32 {
    var v = corners;
    var d = dot(p - v[0], p - v[0]);
    var s = 1.0;
    var j = n - 1u;
    for (var i = 0u; i < n; i = i + 1u) {
        let a = v[i];
        let b = v[j];
        let e = b - a;
        let w = p - a;
        let q = w - e * clamp(dot(w, e) / dot(e, e), 0.0, 1.0);
        d = min(d, dot(q, q));
        let c0 = p.y >= a.y;
        let c1 = p.y < b.y;
        let c2 = e.x * w.y > e.y * w.x;
        if (c0 && c1 && c2) || (!c0 && !c1 && !c2) {
            s = -s;
        }
        j = i;
    }
    return s * sqrt(d);
}

// Exact SDF of an extrusion from the section's SDF d2 and the signed distance h to the slab
// between its caps along the extrusion axis (|axis - centre| - half_length).
fn obj_extrude(d2: f32, h: f32) -> f32 {
    let w = vec2<f32>(d2, h);
    return min(max(w.x, w.y), 0.0) + length(max(w, vec2<f32>(0.0)));
}

// Signed distance (mm, negative inside) from p (object frame) to built-in solid `id`.
// Twin: Solid::sdf in src/object/solids.rs.
fn solid_sdf(id: u32, p: vec3<f32>) -> f32 {
    let r = length(p.xy);
    var d = OBJ_FAR;
    switch id {
        case OBJ_SOLID_CONE: {
            // Cone: the meridian section mirrored about the axis, apex at the origin.
            let section = array<vec2<f32>, 5>(
                vec2<f32>(0.0, 0.0),
                vec2<f32>(-OBJ_CONE_RADIUS, -OBJ_CONE_HEIGHT),
                vec2<f32>(OBJ_CONE_RADIUS, -OBJ_CONE_HEIGHT),
                vec2<f32>(0.0, 0.0),
                vec2<f32>(0.0, 0.0),
            );
            d = obj_sd_polygon(section, 3u, vec2<f32>(r, p.z));
        }
        case OBJ_SOLID_SPHERE: {
            d = length(p - vec3<f32>(0.0, 0.0, -OBJ_SPHERE_RADIUS)) - OBJ_SPHERE_RADIUS;
        }
        case OBJ_SOLID_IRREGULAR_PRISM: {
            d = obj_extrude(
                obj_sd_polygon(OBJ_PRISM_PENTAGON, 5u, p.xy),
                abs(p.z + OBJ_PRISM_HEIGHT / 2.0) - OBJ_PRISM_HEIGHT / 2.0,
            );
        }
        case OBJ_SOLID_CYLINDER: {
            d = obj_sd_box2(
                vec2<f32>(r, p.z),
                vec2<f32>(0.0, -OBJ_CYLINDER_HEIGHT / 2.0),
                vec2<f32>(OBJ_CYLINDER_RADIUS, OBJ_CYLINDER_HEIGHT / 2.0),
            );
        }
        case OBJ_SOLID_EDGE: {
            // Edge: section in (y, z), ridge at the origin, extruded along x.
            let section = array<vec2<f32>, 5>(
                vec2<f32>(0.0, 0.0),
                vec2<f32>(-OBJ_EDGE_WIDTH / 2.0, -OBJ_EDGE_HEIGHT),
                vec2<f32>(OBJ_EDGE_WIDTH / 2.0, -OBJ_EDGE_HEIGHT),
                vec2<f32>(0.0, 0.0),
                vec2<f32>(0.0, 0.0),
            );
            d = obj_extrude(
                obj_sd_polygon(section, 3u, p.yz),
                abs(p.x) - OBJ_EDGE_LENGTH / 2.0,
            );
        }
        case OBJ_SOLID_TUBE: {
            d = obj_sd_box2(
                vec2<f32>(r, p.z),
                vec2<f32>(
                    (OBJ_TUBE_OUTER_RADIUS + OBJ_TUBE_INNER_RADIUS) / 2.0,
                    -OBJ_TUBE_HEIGHT / 2.0,
                ),
                vec2<f32>(
                    (OBJ_TUBE_OUTER_RADIUS - OBJ_TUBE_INNER_RADIUS) / 2.0,
                    OBJ_TUBE_HEIGHT / 2.0,
                ),
            );
        }
        case OBJ_SOLID_SLAB: {
            d = obj_sd_box3(
                p,
                vec3<f32>(0.0, 0.0, -OBJ_SLAB_Z / 2.0),
                vec3<f32>(OBJ_SLAB_X / 2.0, OBJ_SLAB_Y / 2.0, OBJ_SLAB_Z / 2.0),
            );
        }
        case OBJ_SOLID_TORUS: {
            d = length(vec2<f32>(r - OBJ_TORUS_MAJOR_RADIUS, p.z + OBJ_TORUS_MINOR_RADIUS))
                - OBJ_TORUS_MINOR_RADIUS;
        }
        case OBJ_SOLID_DISC: {
            d = obj_sd_box2(
                vec2<f32>(r, p.z),
                vec2<f32>(0.0, -OBJ_DISC_THICKNESS / 2.0),
                vec2<f32>(OBJ_DISC_RADIUS, OBJ_DISC_THICKNESS / 2.0),
            );
        }
        default: {}
    }
    return d;
}
