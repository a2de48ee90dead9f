//! Objects: the built-in solids' SDFs against their own meshes, and the generated assets.
//! The WGSL twin is tested in tests/objects_wgsl.rs, loading and placing in
//! tests/objects_loading.rs.

mod object_support;

use geltip::object::{dims, write_builtin_objects, Mesh, SdfGrid, Solid};
use glam::DVec3;
use object_support::*;

/// Distance from `p` to the nearest triangle of `mesh`, by brute force.
fn brute_distance(mesh: &Mesh, p: DVec3) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            point_triangle_distance(p, a, b, c)
        })
        .fold(f64::INFINITY, f64::min)
}

// ---------------------------------------------------------------------------------------
// Analytic SDFs against the meshes.

#[test]
fn analytic_sdf_agrees_with_sdf_baked_from_its_mesh() {
    let mut rng = Rng(11);
    for s in Solid::ALL {
        let mesh = s.mesh();
        let grid = SdfGrid::bake(&mesh, VOXEL).unwrap();
        let (lo, hi) = test_box(s);
        let (mut checked, mut worst) = (0, 0.0f64);
        while checked < 3000 {
            let p = rng.in_box(lo, hi);
            let exact = s.sdf(p);
            if exact.abs() > 1.0 {
                continue;
            }
            checked += 1;
            let err = (grid.sample(p) - exact).abs();
            worst = worst.max(err);
            assert!(
                err < 1.5 * VOXEL,
                "{s}: at {p} analytic {exact} but baked {}",
                grid.sample(p)
            );
        }
        // Away from the sharp features the agreement is much better than the bound.
        println!("{s}: worst |baked - analytic| near the surface = {worst:.4} mm");
    }
}

#[test]
fn baked_voxels_hold_exact_distances_to_the_mesh_everywhere() {
    // Not just in the exact band: the sweeps must find the nearest triangle far away too.
    let mut rng = Rng(17);
    for s in Solid::ALL {
        let mesh = s.mesh();
        let grid = SdfGrid::bake(&mesh, VOXEL).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..800 {
            let v = [0, 1, 2].map(|a| (rng.next() * f64::from(grid.dims[a])) as u32);
            let p = grid.voxel_centre(v[0], v[1], v[2]);
            let brute = brute_distance(&mesh, p);
            let got = f64::from(grid.values[grid.index(v[0], v[1], v[2])]);
            // Within the exact band (2 voxels) exact up to f32; beyond it the distance to
            // the nearest triangle the sweeps found: never less than the truth, and at most
            // a few micrometres more where many triangles compete (inside the sphere).
            let err = got.abs() - brute;
            worst = worst.max(err.abs());
            let tol = if brute <= 2.0 * VOXEL { 1e-5 } else { 0.02 };
            assert!(
                err > -1e-5 && err < tol,
                "{s}: voxel {v:?} at {p}: |{got}| but the mesh is {brute} away"
            );
            if brute > 0.05 {
                assert_eq!(got < 0.0, s.sdf(p) < 0.0, "{s}: voxel {v:?} at {p}: sign");
            }
        }
        println!("{s}: worst voxel error {worst:.2e} mm");
    }
}

#[test]
fn signs_at_known_inside_and_outside_points() {
    use Solid::*;
    let inside: [(Solid, [f64; 3]); 7] = [
        (Cone, [0.0, 0.0, -8.0]),
        (Sphere, [0.0, 0.0, -5.0]),
        (IrregularPrism, [0.0, 0.0, -5.0]),
        (Cylinder, [0.0, 0.0, -5.0]),
        (Edge, [0.0, 0.0, -4.0]),
        (Tube, [2.5, 0.0, -5.0]),
        (Slab, [0.0, 0.0, -1.5]),
    ];
    let outside: [(Solid, [f64; 3]); 7] = [
        (Cone, [4.0, 0.0, -2.0]),
        (Sphere, [4.0, 4.0, -1.0]),
        (IrregularPrism, [3.4, 3.2, -5.0]),
        (Cylinder, [2.5, 0.0, -5.0]),
        (Edge, [0.0, 2.5, -1.0]),
        (Tube, [0.0, 0.0, -5.0]),
        (Slab, [0.0, 0.0, -4.0]),
    ];
    for s in Solid::ALL {
        let grid = SdfGrid::bake(&s.mesh(), VOXEL).unwrap();
        let above = DVec3::new(0.0, 0.0, 1.0);
        assert!(s.sdf(above) > 0.9 && grid.sample(above) > 0.9, "{s}: above");
        for (t, p) in inside {
            if t == s {
                let p = DVec3::from(p);
                assert!(s.sdf(p) < -0.4, "{s}: {p} should be inside");
                assert!(grid.sample(p) < -0.4, "{s}: {p} should be inside the bake");
            }
        }
        for (t, p) in outside {
            if t == s {
                let p = DVec3::from(p);
                assert!(s.sdf(p) > 0.2, "{s}: {p} should be outside");
                assert!(grid.sample(p) > 0.2, "{s}: {p} should be outside the bake");
            }
        }
    }
}

#[test]
fn every_solid_touches_the_origin_from_below() {
    for s in Solid::ALL {
        let mesh = s.mesh();
        let max_z = mesh.positions.iter().map(|p| p.z).fold(f64::MIN, f64::max);
        assert_eq!(max_z, 0.0, "{s}: mesh top");
        assert_eq!(mesh.top(), DVec3::ZERO, "{s}: the mesh's top is the origin");
        assert_eq!(mesh.placed_for_contact(), mesh, "{s}: already placed");
        let at_origin = s.sdf(DVec3::ZERO);
        if s == Solid::Tube {
            // A ring: the origin is the centre of the hole, the rim is at z = 0.
            assert_eq!(at_origin, dims::TUBE_INNER_RADIUS);
            assert_eq!(s.sdf(DVec3::new(2.5, 0.0, 0.0)), 0.0);
        } else {
            assert!(at_origin.abs() < 1e-12, "{s}: sdf(origin) = {at_origin}");
        }
        // Nothing of the solid is above z = 0.
        let mut rng = Rng(5);
        let (lo, hi) = test_box(s);
        for _ in 0..2000 {
            let p = rng.in_box(DVec3::new(lo.x, lo.y, 1e-3), hi);
            assert!(s.sdf(p) >= p.z - 1e-12, "{s}: {p}");
        }
    }
}

#[test]
fn analytic_sdfs_are_1_lipschitz() {
    let mut rng = Rng(23);
    for s in Solid::ALL {
        let (lo, hi) = test_box(s);
        for k in 0..20000 {
            let a = rng.in_box(lo, hi);
            // Half the pairs close together, where a kink in the field would show.
            let b = if k % 2 == 0 {
                a + (rng.in_box(DVec3::splat(-1.0), DVec3::splat(1.0))) * 0.05
            } else {
                rng.in_box(lo, hi)
            };
            let (da, db) = (s.sdf(a), s.sdf(b));
            assert!(
                (da - db).abs() <= (a - b).length() * (1.0 + 1e-9) + 1e-12,
                "{s}: |sdf({a}) - sdf({b})| = {} > {}",
                (da - db).abs(),
                (a - b).length()
            );
        }
    }
}

#[test]
fn analytic_sdfs_are_exact_distances_to_the_mesh_surface() {
    // Outside points: the SDF equals the distance to the (finely tessellated) mesh, up to
    // the tessellation's chord error. Brute force over all triangles.
    let mut rng = Rng(31);
    for s in Solid::ALL {
        let mesh = s.mesh();
        let (lo, hi) = test_box(s);
        let mut n = 0;
        while n < 60 {
            let p = rng.in_box(lo, hi);
            let d = s.sdf(p);
            if d.abs() > 1.2 {
                continue;
            }
            n += 1;
            let brute = brute_distance(&mesh, p);
            // Chord error of 64 segments (and 32 rings) on radius 5: below 0.02 mm.
            assert!(
                (brute - d.abs()).abs() < 0.02,
                "{s}: at {p} |sdf| = {} but mesh distance {brute}",
                d.abs()
            );
        }
    }
}

/// Independent point-triangle distance for the brute-force test: the closest of the
/// interior projection (when it falls inside) and the three edges.
fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let seg = |a: DVec3, b: DVec3| {
        let e = b - a;
        let t = ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        (p - (a + e * t)).length()
    };
    let mut best = seg(a, b).min(seg(b, c)).min(seg(c, a));
    let n = (b - a).cross(c - a);
    if n.length_squared() > 0.0 {
        let n = n.normalize();
        let q = p - n * (p - a).dot(n);
        let inside = (b - a).cross(q - a).dot(n) >= 0.0
            && (c - b).cross(q - b).dot(n) >= 0.0
            && (a - c).cross(q - c).dot(n) >= 0.0;
        if inside {
            best = best.min((p - q).length());
        }
    }
    best
}

// ---------------------------------------------------------------------------------------
// Generated assets.

#[test]
fn builtin_object_assets_match_the_code() {
    let dir = temp_dir("assets");
    write_builtin_objects(&dir).unwrap();
    for s in Solid::ALL {
        let file = format!("{}.obj", s.name());
        let fresh = std::fs::read(dir.join(&file)).unwrap();
        let committed =
            std::fs::read(repo_path("assets/objects").join(&file)).unwrap_or_else(|e| {
                panic!(
                    "assets/objects/{file}: {e}; regenerate with \
                 `cargo test --test objects -- --ignored regenerate_builtin_object_assets`"
                )
            });
        assert!(
            fresh == committed,
            "assets/objects/{file} differs from what the code generates; regenerate with \
             `cargo test --test objects -- --ignored regenerate_builtin_object_assets`"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes `assets/objects/*.obj` from the code. Run on purpose only.
#[test]
#[ignore = "writes into assets/objects"]
fn regenerate_builtin_object_assets() {
    write_builtin_objects(&repo_path("assets/objects")).unwrap();
}

/// Prints bake timings (run with `--ignored --nocapture`, ideally `--release`).
#[test]
#[ignore = "timing report"]
fn bake_timings() {
    for s in Solid::ALL {
        let mesh = s.mesh();
        for voxel in [0.5, 0.25, 0.125] {
            let t = std::time::Instant::now();
            let grid = SdfGrid::bake(&mesh, voxel).unwrap();
            println!(
                "{s:>16}: {:5} triangles, voxel {voxel:5} mm, grid {:?} = {:8} voxels: {:7.1} ms",
                mesh.triangles.len(),
                grid.dims,
                grid.values.len(),
                t.elapsed().as_secs_f64() * 1e3
            );
        }
    }
}
