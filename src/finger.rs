//! The finger: an open cylinder of radius r for z <= d, capped by a hemisphere of radius r
//! centred at (0, 0, d). The camera's optical centre is the origin and it looks along +z.
//!
//! The surface is parameterised without seams by unrolling it around the tip: `s` is the arc
//! length from the tip along a meridian and `phi` the azimuth. The renderer stores the
//! elastomer's deformation on the disc `(s cos phi, s sin phi)`, which has no singularity at
//! the tip and is C1 across the sphere/cylinder junction (s = pi r / 2).

use glam::{DVec2, DVec3};
use serde::Serialize;
use std::f64::consts::FRAC_PI_2;

/// Which part of the finger a surface point lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Region {
    Hemisphere,
    Cylinder,
}

impl Region {
    /// The name used in JSON output.
    pub fn name(self) -> &'static str {
        match self {
            Region::Hemisphere => "hemisphere",
            Region::Cylinder => "cylinder",
        }
    }
}

/// A point on the (undeformed) finger surface with its outward unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    pub point: DVec3,
    pub normal: DVec3,
    pub region: Region,
}

/// Seam-free surface coordinates: arc length from the tip (mm) and azimuth (radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceCoord {
    pub s: f64,
    pub phi: f64,
}

impl SurfaceCoord {
    /// The unrolled-disc coordinates (s cos phi, s sin phi), in mm.
    pub fn to_disc(self) -> DVec2 {
        DVec2::new(self.s * self.phi.cos(), self.s * self.phi.sin())
    }

    /// Inverse of [`SurfaceCoord::to_disc`]; the tip (origin of the disc) gets phi = 0.
    pub fn from_disc(disc: DVec2) -> Self {
        SurfaceCoord {
            s: disc.length(),
            phi: disc.y.atan2(disc.x),
        }
    }
}

/// The finger's geometry, in millimetres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Finger {
    /// r: radius of the cylinder and of the hemisphere.
    pub radius: f64,
    /// d: distance from the camera centre to the hemisphere's centre along the axis.
    pub cylinder_length: f64,
    /// T: thickness of the elastomer shell on the inside of the surface.
    pub shell_thickness: f64,
}

impl Finger {
    /// The hemisphere's centre (0, 0, d).
    pub fn sphere_centre(&self) -> DVec3 {
        DVec3::new(0.0, 0.0, self.cylinder_length)
    }

    /// The tip of the finger (0, 0, d + r).
    pub fn tip(&self) -> DVec3 {
        DVec3::new(0.0, 0.0, self.cylinder_length + self.radius)
    }

    /// Arc length from the tip to the sphere/cylinder junction: pi r / 2.
    pub fn junction_s(&self) -> f64 {
        FRAC_PI_2 * self.radius
    }

    /// Arc length of the paper's "rotation about the tip" by `angle_rad` (0 = tip, pi/2 = junction).
    pub fn s_of_rotation(&self, angle_rad: f64) -> f64 {
        self.radius * angle_rad
    }

    /// Arc length of the paper's "translation along the side" by `mm` below the junction.
    pub fn s_of_translation(&self, mm: f64) -> f64 {
        self.junction_s() + mm
    }

    /// The surface point at arc length `s` (>= 0) from the tip and azimuth `phi`.
    pub fn point_at(&self, coord: SurfaceCoord) -> SurfacePoint {
        let (sin_phi, cos_phi) = coord.phi.sin_cos();
        self.point_towards(coord.s, cos_phi, sin_phi)
    }

    /// The surface point at `disc`, a position on the unrolled disc (arc length from the tip
    /// as its length, azimuth as its angle): `point_at(SurfaceCoord::from_disc(disc))`
    /// without the azimuth's atan2, sine and cosine (its cosine and sine are the position's
    /// direction), as the shaders' `surface_at_disc` does. For the scans that visit
    /// thousands of disc positions a contact.
    pub fn point_at_disc(&self, disc: DVec2) -> SurfacePoint {
        let s = disc.length();
        if s > 0.0 {
            self.point_towards(s, disc.x / s, disc.y / s)
        } else {
            // atan2(0, 0) = 0: the azimuth from_disc gives the tip.
            self.point_towards(0.0, 1.0, 0.0)
        }
    }

    /// The surface point at arc length `s` along the meridian of azimuth phi, given as its
    /// cosine and sine.
    pub(crate) fn point_towards(&self, s: f64, cos_phi: f64, sin_phi: f64) -> SurfacePoint {
        let (r, d) = (self.radius, self.cylinder_length);
        if s <= self.junction_s() {
            let beta = s / r;
            let (sin_b, cos_b) = beta.sin_cos();
            let normal = DVec3::new(sin_b * cos_phi, sin_b * sin_phi, cos_b);
            SurfacePoint {
                point: self.sphere_centre() + r * normal,
                normal,
                region: Region::Hemisphere,
            }
        } else {
            let z = d - (s - self.junction_s());
            SurfacePoint {
                point: DVec3::new(r * cos_phi, r * sin_phi, z),
                normal: DVec3::new(cos_phi, sin_phi, 0.0),
                region: Region::Cylinder,
            }
        }
    }

    /// Unit tangents at `coord`: along the meridian away from the tip (d/ds), and along the
    /// azimuth (d/dphi, normalised). At the tip they are the limits along azimuth `phi`.
    pub fn tangents_at(&self, coord: SurfaceCoord) -> (DVec3, DVec3) {
        let (sin_phi, cos_phi) = coord.phi.sin_cos();
        let e_phi = DVec3::new(-sin_phi, cos_phi, 0.0);
        let e_s = if coord.s <= self.junction_s() {
            let (sin_b, cos_b) = (coord.s / self.radius).sin_cos();
            DVec3::new(cos_b * cos_phi, cos_b * sin_phi, -sin_b)
        } else {
            DVec3::new(0.0, 0.0, -1.0)
        };
        (e_s, e_phi)
    }

    /// Coordinates of the surface point closest to `p` (its foot along the surface normal).
    /// Defined for every point off the axis above the junction and every point off the axis
    /// below it; points on the axis below the junction get phi = 0.
    pub fn coord_of(&self, p: DVec3) -> SurfaceCoord {
        let phi = p.y.atan2(p.x);
        let rho = p.x.hypot(p.y);
        if p.z > self.cylinder_length {
            let beta = rho.atan2(p.z - self.cylinder_length);
            SurfaceCoord {
                s: self.radius * beta,
                phi,
            }
        } else {
            SurfaceCoord {
                s: self.junction_s() + (self.cylinder_length - p.z),
                phi,
            }
        }
    }

    /// Signed distance from `p` to the surface: negative inside the finger, positive outside.
    /// Exact for the infinitely long open-bottomed finger (a convex solid).
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        if p.z > self.cylinder_length {
            (p - self.sphere_centre()).length() - self.radius
        } else {
            p.x.hypot(p.y) - self.radius
        }
    }

    /// Where the ray from the camera centre along the unit direction `dir` meets the surface:
    /// the distance t and the region. Every ray that is not straight back (dir.z > -1) meets
    /// it exactly once, because the camera sits inside a convex solid.
    pub fn ray_hit(&self, dir: DVec3) -> Option<(f64, Region)> {
        let (r, d) = (self.radius, self.cylinder_length);
        let sin_t = dir.x.hypot(dir.y);
        let cos_t = dir.z;
        // The cylinder is met at height z = r cot(theta); it is part of the finger while z <= d.
        // Written without dividing so that it holds at theta = 0 and past 90 degrees.
        if r * cos_t <= d * sin_t {
            if sin_t <= 0.0 {
                return None;
            }
            Some((r / sin_t, Region::Cylinder))
        } else {
            // |t dir - c|^2 = r^2 with c = (0,0,d): t^2 - 2 d cos t + d^2 - r^2 = 0, far root.
            let disc = r * r - d * d * sin_t * sin_t;
            Some((d * cos_t + disc.max(0.0).sqrt(), Region::Hemisphere))
        }
    }

    /// The surface point seen along `dir` from the camera centre.
    pub fn surface_along(&self, dir: DVec3) -> Option<SurfacePoint> {
        let (t, region) = self.ray_hit(dir)?;
        let point = t * dir;
        let normal = match region {
            Region::Hemisphere => (point - self.sphere_centre()) / self.radius,
            Region::Cylinder => DVec3::new(point.x / self.radius, point.y / self.radius, 0.0),
        };
        Some(SurfacePoint {
            point,
            normal,
            region,
        })
    }

    /// Angle off the optical axis at which the camera sees the junction ring: atan(r / d).
    pub fn junction_theta(&self) -> f64 {
        self.radius.atan2(self.cylinder_length)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn finger() -> Finger {
        Finger {
            radius: 7.5,
            cylinder_length: 20.0,
            shell_thickness: 1.5,
        }
    }

    #[test]
    fn a_disc_position_gives_the_point_of_its_coordinates() {
        let f = finger();
        let mut checked = 0;
        for i in -40..=40 {
            for j in -40..=40 {
                let disc =
                    DVec2::new(i as f64, j as f64) * 0.77 + DVec2::new(1e-3, 0.0) * (i % 3) as f64;
                let a = f.point_at_disc(disc);
                let b = f.point_at(SurfaceCoord::from_disc(disc));
                assert!((a.point - b.point).length() < 1e-12, "{disc}");
                assert!((a.normal - b.normal).length() < 1e-12, "{disc}");
                assert_eq!(a.region, b.region, "{disc}");
                checked += 1;
            }
        }
        let tip = f.point_at_disc(DVec2::ZERO);
        assert_eq!(
            tip.point,
            f.point_at(SurfaceCoord { s: 0.0, phi: 0.0 }).point
        );
        assert!(checked > 6000);
    }

    #[test]
    fn parameterisation_round_trips_on_both_parts() {
        let f = finger();
        for &s in &[
            0.0,
            0.3,
            5.0,
            f.junction_s() - 1e-9,
            f.junction_s(),
            f.junction_s() + 1e-9,
            20.0,
            30.0,
        ] {
            for &phi in &[-3.0, -1.0, 0.0, 0.5, 2.9] {
                let sp = f.point_at(SurfaceCoord { s, phi });
                assert!(
                    f.signed_distance(sp.point).abs() < 1e-12,
                    "s={s} off the surface"
                );
                assert!((sp.normal.length() - 1.0).abs() < 1e-12);
                let back = f.coord_of(sp.point);
                assert!((back.s - s).abs() < 1e-9, "s={s} came back as {}", back.s);
                if s > 0.0 {
                    assert!(
                        (back.phi - phi).abs() < 1e-9,
                        "phi={phi} came back as {}",
                        back.phi
                    );
                }
            }
        }
    }

    #[test]
    fn surface_is_continuous_and_smooth_across_the_junction() {
        let f = finger();
        let eps = 1e-7;
        let a = f.point_at(SurfaceCoord {
            s: f.junction_s() - eps,
            phi: 0.4,
        });
        let b = f.point_at(SurfaceCoord {
            s: f.junction_s() + eps,
            phi: 0.4,
        });
        assert!((a.point - b.point).length() < 3.0 * eps);
        assert!((a.normal - b.normal).length() < 1e-6);
        assert_eq!(a.region, Region::Hemisphere);
        assert_eq!(b.region, Region::Cylinder);
    }

    #[test]
    fn tangents_are_derivatives_of_the_parameterisation() {
        let f = finger();
        for &s in &[0.0, 4.0, 14.0, 25.0] {
            let c = SurfaceCoord { s, phi: 1.1 };
            let (e_s, e_phi) = f.tangents_at(c);
            let h = 1e-6;
            let ds = (f.point_at(SurfaceCoord { s: s + h, ..c }).point - f.point_at(c).point) / h;
            assert!((ds - e_s).length() < 1e-5, "d/ds at s={s}");
            assert!(e_phi.dot(f.point_at(c).normal).abs() < 1e-12);
            assert!(e_s.dot(e_phi).abs() < 1e-12);
        }
    }

    #[test]
    fn rays_hit_the_region_their_angle_says() {
        let f = finger();
        let tj = f.junction_theta();
        for &(theta, want) in &[
            (0.0, Region::Hemisphere),
            (tj - 1e-6, Region::Hemisphere),
            (tj + 1e-6, Region::Cylinder),
            (1.5, Region::Cylinder),
            (2.0, Region::Cylinder),
        ] {
            let dir = DVec3::new(theta.sin(), 0.0, theta.cos());
            let sp = f.surface_along(dir).unwrap();
            assert_eq!(sp.region, want, "theta={theta}");
            assert!(f.signed_distance(sp.point).abs() < 1e-12);
        }
        assert!(f.ray_hit(DVec3::new(0.0, 0.0, -1.0)).is_none());
    }
}
