//! `geltip render`: one tactile image (an object pressed into the finger, a scene of
//! several, or the empty finger), its labels and depth map.

use anyhow::{anyhow, Context, Result};
use clap::Args;
use geltip::object::ObjectCache;
use geltip::output;
use geltip::render::background::{composite, load_background, Background};
use geltip::render::gpu::Renderer;
use geltip::render::{Frame, Press};
use geltip::scene::{load_scene, numbers, pose_numbers, At, ContactSpec};
use geltip::sensor::Sensor;
use geltip::GeltipError;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args)]
pub struct RenderArgs {
    /// Preset name or path to a sensor TOML file.
    #[arg(long)]
    sensor: String,
    /// Render the empty finger (the reference frame detectors subtract).
    #[arg(long, conflicts_with_all = ["object", "at", "depth", "azimuth", "spin", "labels", "pose", "scene", "tilt", "tilt_towards"])]
    reference: bool,
    /// A built-in solid (cone, sphere, irregular-prism, cylinder, edge, tube, slab, torus,
    /// disc), a sized primitive (sphere:r=5, capsule:r=2,l=8, cylinder:r=2,l=10,
    /// box:x=10,y=6,z=4, ellipsoid:x=8,y=6,z=4; mm, top at the contact, axis along the
    /// normal) or a mesh file (.obj, .gltf, .glb) whose +z points at the finger.
    #[arg(long, required_unless_present_any = ["reference", "scene"], conflicts_with = "scene")]
    object: Option<String>,
    /// Where: rotation=<deg> about the tip (0 = tip, 90 = junction), translation=<mm>
    /// along the side below the junction, or s=<mm> of arc length from the tip.
    #[arg(long, required_unless_present_any = ["reference", "pose", "scene"], conflicts_with_all = ["pose", "scene"])]
    at: Option<String>,
    /// Azimuth of the contact about the finger's axis, degrees (0 = image +x).
    #[arg(long, default_value_t = 0.0)]
    azimuth: f64,
    /// The object's rotation about the contact normal, degrees.
    #[arg(long, default_value_t = 0.0)]
    spin: f64,
    /// Tilt of the object's axis away from the contact normal, degrees (-90..90).
    #[arg(long, default_value_t = 0.0)]
    tilt: f64,
    /// Direction the object's outer end leans to, in the tangent plane: degrees from the
    /// meridian (away from the tip) towards increasing azimuth.
    #[arg(long = "tilt-towards", default_value_t = 0.0)]
    tilt_towards: f64,
    /// Press depth beyond the object's first touch of the undeformed finger, along the
    /// surface normal, mm.
    #[arg(long, required_unless_present_any = ["reference", "pose", "scene"], conflicts_with_all = ["pose", "scene"])]
    depth: Option<f64>,
    /// A rigid pose in the camera frame instead of --at/--depth: 16 numbers (row-major
    /// 4x4 matrix) or 7 (x y z qw qx qy qz), comma- or space-separated; the depth is
    /// what the pose implies (in the labels). The labels' `pose` loads back as is.
    #[arg(long, allow_hyphen_values = true, conflicts_with_all = ["azimuth", "spin", "tilt", "tilt_towards", "scene"])]
    pose: Option<String>,
    /// With --pose: the direction the object moves in to press the finger, 3 numbers in the
    /// camera frame (comma- or space-separated); the depth is measured along it. Default:
    /// the object's own +z axis.
    #[arg(long, requires = "pose", allow_hyphen_values = true)]
    approach: Option<String>,
    /// Several contacts in one frame: a JSON (.json) or TOML file listing `contacts`,
    /// each with the flags' names (object, at, depth, azimuth, spin, tilt, tilt_towards)
    /// or object and pose. The labels become a list plus the union mask.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Output PNG.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Ground truth as JSON (object, point, pixel, normal, depth_mm, region, mask...).
    #[arg(long)]
    labels: Option<PathBuf>,
    /// Indentation (mm) each pixel sees, as a float32 NumPy array (height x width).
    #[arg(long = "depth-map")]
    depth_map: Option<PathBuf>,
    /// A real sensor's empty frame (an image of the sensor's size): the output is it plus
    /// the render's change from the rendered empty finger, as `geltip dataset --background`
    /// makes its images. With --reference the output is the background itself, plus fresh
    /// noise when the sensor file sets render.noise (the background's own noise stays).
    /// Labels and depth maps do not change.
    #[arg(long)]
    background: Option<PathBuf>,
}

/// Renders the frame, writes it (and the labels and depth map asked for) and prints the
/// labels as JSON.
pub fn render(args: RenderArgs) -> Result<()> {
    let sensor = Sensor::load(&args.sensor)?;
    let background = args
        .background
        .as_deref()
        .map(|path| load_background(path, &sensor))
        .transpose()?;
    if args.reference {
        let mut renderer = Renderer::new(&sensor)?;
        let frame = renderer.render_empty()?;
        write_frame(&frame, &args, background.as_ref(), &renderer)?;
        println!("{}", json!({ "image": args.output, "reference": true }));
        return Ok(());
    }
    // Every contact is checked on the finger before paying for the GPU's start-up.
    let presses = match &args.scene {
        Some(path) => load_scene(path, &sensor)?,
        None => vec![args.press(&sensor)?],
    };
    let mut renderer = Renderer::new(&sensor)?;
    let (frame, truths) = renderer.render_scene(&presses)?;
    write_frame(&frame, &args, background.as_ref(), &renderer)?;
    let labels = if args.scene.is_some() {
        geltip::render::scene_labels(&frame, &truths)
    } else {
        truths[0].to_json()
    };
    if let Some(path) = &args.labels {
        output::write_json(path, &labels)?;
    }
    if truths.iter().any(|t| t.over_pressed) {
        eprintln!(
            "warning: the object pressed the gel against the rigid shell (depth beyond {} mm)",
            sensor.finger.shell_thickness
        );
    }
    println!("{labels}");
    Ok(())
}

impl RenderArgs {
    /// The contact the flags describe, in the library's terms.
    fn spec(&self) -> Result<ContactSpec> {
        let object = self.object.clone().context("--object is required")?;
        if let Some(text) = &self.pose {
            let approach = match &self.approach {
                Some(text) => Some(numbers("approach", text).map_err(under_flag)?),
                None => None,
            };
            return Ok(ContactSpec {
                object,
                pose: Some(pose_numbers(text).map_err(under_flag)?),
                approach,
                ..ContactSpec::default()
            });
        }
        Ok(ContactSpec {
            object,
            at: Some(At::Text(self.at.clone().context("--at is required")?)),
            azimuth: Some(self.azimuth),
            spin: Some(self.spin),
            tilt: Some(self.tilt),
            tilt_towards: Some(self.tilt_towards),
            depth: Some(self.depth.context("--depth is required")?),
            pose: None,
            approach: None,
        })
    }

    /// The press the flags describe, placed on `sensor`'s finger to check it; an error about
    /// one of the contact's fields names its flag.
    fn press(&self, sensor: &Sensor) -> Result<Press> {
        let press = self
            .spec()?
            .press(&mut ObjectCache::default())
            .map_err(under_flag)?;
        press.pose(sensor).map_err(under_flag)?;
        Ok(press)
    }
}

/// A contact field's error named by the flag that gives it (`depth` -> `--depth`).
fn under_flag(e: GeltipError) -> anyhow::Error {
    match e {
        GeltipError::InvalidContact { field, reason } => {
            anyhow!("--{}: {reason}", field.replace('_', "-"))
        }
        other => other.into(),
    }
}

/// Writes the image (on `background` when given, against `renderer`'s empty finger) and
/// the depth map asked for.
fn write_frame(
    frame: &Frame,
    args: &RenderArgs,
    background: Option<&Background>,
    renderer: &Renderer,
) -> Result<()> {
    let rgb = match background {
        Some(b) => composite(&b.image, frame, renderer.reference())?,
        None => frame.to_rgb(),
    };
    output::write_png_rgb8(&args.output, rgb.width(), rgb.height(), rgb.as_raw())?;
    if let Some(path) = &args.depth_map {
        output::write_npy_f32(path, frame.width, frame.height, &frame.indentation)?;
    }
    Ok(())
}
