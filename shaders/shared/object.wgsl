// object.wgsl: signed distance functions of the built-in test solids and of the sized
// primitives.
//
// Twin of src/object/solids.rs: every constant OBJ_X here is `dims::X` there, and every
// obj_* function mirrors the Rust function of the same name (without the prefix). Change
// both together; tests/objects_wgsl.rs checks that the constants agree and that this file
// validates with naga. The primitives' twin is src/object/primitive.rs (primitive_sdf,
// OBJ_PRIMITIVE_*), held to it by tests/primitives.rs.
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

// Sized primitives (Primitive::kind, from FIRST_PRIMITIVE_KIND): their sizes come in the
// frame's object_size (Primitive::gpu_size).
const OBJ_PRIMITIVE_SPHERE: u32 = 10u;
const OBJ_PRIMITIVE_CAPSULE: u32 = 11u;
const OBJ_PRIMITIVE_CYLINDER: u32 = 12u;
const OBJ_PRIMITIVE_BOX: u32 = 13u;
const OBJ_PRIMITIVE_ELLIPSOID: u32 = 14u;

// Bisection steps at most in the ellipsoid's closest-point root: f32 converges within about
// 40 from the bracket's width (Rust: ELLIPSOID_MAX_STEPS, for f64).
const OBJ_ELLIPSOID_MAX_STEPS: u32 = 64u;

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

// Signed distance (mm, negative inside) from p (object frame) to the sized primitive of
// kind `kind` with sizes `size` (sphere: r; capsule, cylinder: r, l; box, ellipsoid: their
// half-sizes x, y, z). Its top is at the origin, its centre at (0, 0, -top).
// Twin: Primitive::sdf in src/object/primitive.rs.
fn primitive_sdf(kind: u32, size: vec4<f32>, p: vec3<f32>) -> f32 {
    var d = OBJ_FAR;
    switch kind {
        case OBJ_PRIMITIVE_SPHERE: {
            d = length(p + vec3<f32>(0.0, 0.0, size.x)) - size.x;
        }
        case OBJ_PRIMITIVE_CAPSULE: {
            let c = p + vec3<f32>(0.0, 0.0, size.x + size.y / 2.0);
            d = length(c - vec3<f32>(0.0, 0.0, clamp(c.z, -size.y / 2.0, size.y / 2.0))) - size.x;
        }
        case OBJ_PRIMITIVE_CYLINDER: {
            let c = p + vec3<f32>(0.0, 0.0, size.y / 2.0);
            d = obj_sd_box2(vec2<f32>(length(c.xy), c.z), vec2<f32>(0.0), vec2<f32>(size.x, size.y / 2.0));
        }
        case OBJ_PRIMITIVE_BOX: {
            d = obj_sd_box3(p, vec3<f32>(0.0, 0.0, -size.z), size.xyz);
        }
        case OBJ_PRIMITIVE_ELLIPSOID: {
            d = obj_sd_ellipsoid(p + vec3<f32>(0.0, 0.0, size.z), size.xyz);
        }
        default: {}
    }
    return d;
}

// Exact signed distance from c (relative to the centre) to the ellipsoid of semi-axes e:
// the closest point by Eberly's robust bisection, signed by whether c is inside.
fn obj_sd_ellipsoid(c: vec3<f32>, e: vec3<f32>) -> f32 {
    // By symmetry, the first octant with the axes sorted longest first.
    var a0 = vec2<f32>(e.x, abs(c.x));
    var a1 = vec2<f32>(e.y, abs(c.y));
    var a2 = vec2<f32>(e.z, abs(c.z));
    if a0.x < a1.x {
        let t = a0; a0 = a1; a1 = t;
    }
    if a1.x < a2.x {
        let t = a1; a1 = a2; a2 = t;
    }
    if a0.x < a1.x {
        let t = a0; a0 = a1; a1 = t;
    }
    let q = vec3<f32>(a0.y / a0.x, a1.y / a1.x, a2.y / a2.x);
    let g = dot(q, q) - 1.0;
    let d = obj_distance_to_ellipsoid(vec3<f32>(a0.x, a1.x, a2.x), vec3<f32>(a0.y, a1.y, a2.y));
    return select(d, -d, g < 0.0);
}

// Unsigned distance from y >= 0 to the ellipsoid of semi-axes e.x >= e.y >= e.z.
fn obj_distance_to_ellipsoid(e: vec3<f32>, y: vec3<f32>) -> f32 {
    if y.z > 0.0 {
        if y.y > 0.0 && y.x > 0.0 {
            let z = y / e;
            let g = dot(z, z) - 1.0;
            if g == 0.0 {
                return 0.0;
            }
            let r = vec2<f32>((e.x / e.z) * (e.x / e.z), (e.y / e.z) * (e.y / e.z));
            let s = obj_ellipsoid_root(r, z, g);
            let x = vec3<f32>(r.x * y.x / (s + r.x), r.y * y.y / (s + r.y), y.z / (s + 1.0));
            return length(x - y);
        }
        if y.y > 0.0 {
            return obj_distance_to_ellipse(e.yz, y.yz);
        }
        if y.x > 0.0 {
            return obj_distance_to_ellipse(e.xz, y.xz);
        }
        return abs(y.z - e.z);
    }
    // On the plane of the two longest axes: inside the region whose closest point lies off
    // that plane, or else the ellipse's problem.
    let den = vec2<f32>(e.x * e.x - e.z * e.z, e.y * e.y - e.z * e.z);
    let num = vec2<f32>(e.x * y.x, e.y * y.y);
    if num.x < den.x && num.y < den.y {
        let q = num / den;
        let discr = 1.0 - dot(q, q);
        if discr > 0.0 {
            let x = vec3<f32>(e.x * q.x, e.y * q.y, e.z * sqrt(discr));
            return length(x - vec3<f32>(y.x, y.y, 0.0));
        }
    }
    return obj_distance_to_ellipse(e.xy, y.xy);
}

// Unsigned distance from y >= 0 to the ellipse of semi-axes e.x >= e.y.
fn obj_distance_to_ellipse(e: vec2<f32>, y: vec2<f32>) -> f32 {
    if y.y > 0.0 {
        if y.x > 0.0 {
            let z = y / e;
            let g = dot(z, z) - 1.0;
            if g == 0.0 {
                return 0.0;
            }
            let r0 = (e.x / e.y) * (e.x / e.y);
            let s = obj_ellipse_root(r0, z, g);
            let x = vec2<f32>(r0 * y.x / (s + r0), y.y / (s + 1.0));
            return length(x - y);
        }
        return abs(y.y - e.y);
    }
    let num = e.x * y.x;
    let den = e.x * e.x - e.y * e.y;
    if num < den {
        let q = num / den;
        let x = vec2<f32>(e.x * q, e.y * sqrt(1.0 - q * q));
        return length(x - vec2<f32>(y.x, 0.0));
    }
    return abs(y.x - e.x);
}

// The root s of sum((r_i z_i / (s + r_i))^2) - 1 (r = 1 for the last axis) by bisection of
// its bracket; g is its value at s = 0.
fn obj_ellipsoid_root(r: vec2<f32>, z: vec3<f32>, g: f32) -> f32 {
    let n = r * z.xy;
    var lo = z.z - 1.0;
    var hi = select(length(vec3<f32>(n, z.z)) - 1.0, 0.0, g < 0.0);
    var s = 0.5 * (lo + hi);
    for (var i = 0u; i < OBJ_ELLIPSOID_MAX_STEPS; i++) {
        s = 0.5 * (lo + hi);
        if s == lo || s == hi {
            break;
        }
        let a = n.x / (s + r.x);
        let b = n.y / (s + r.y);
        let c = z.z / (s + 1.0);
        let f = a * a + b * b + c * c - 1.0;
        if f > 0.0 {
            lo = s;
        } else if f < 0.0 {
            hi = s;
        } else {
            break;
        }
    }
    return s;
}

// As obj_ellipsoid_root, for an ellipse.
fn obj_ellipse_root(r0: f32, z: vec2<f32>, g: f32) -> f32 {
    let n0 = r0 * z.x;
    var lo = z.y - 1.0;
    var hi = select(length(vec2<f32>(n0, z.y)) - 1.0, 0.0, g < 0.0);
    var s = 0.5 * (lo + hi);
    for (var i = 0u; i < OBJ_ELLIPSOID_MAX_STEPS; i++) {
        s = 0.5 * (lo + hi);
        if s == lo || s == hi {
            break;
        }
        let a = n0 / (s + r0);
        let c = z.y / (s + 1.0);
        let f = a * a + c * c - 1.0;
        if f > 0.0 {
            lo = s;
        } else if f < 0.0 {
            hi = s;
        } else {
            break;
        }
    }
    return s;
}
