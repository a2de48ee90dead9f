//! The commands of the `geltip` binary: their arguments (clap) and one function each, in
//! the module of what they run.

pub mod calibrate;
pub mod dataset;
pub mod evaluate;
pub mod imprint;
pub mod jobs;
pub mod localise;
pub mod progress;
pub mod render;
pub mod sensor;

use clap::{Parser, Subcommand};
use geltip::GeltipError;

#[derive(Parser)]
#[command(
    name = "geltip",
    version,
    about = "Simulator of the GelTip optical tactile sensor"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// List the sensor presets.
    Sensors,
    /// Map a pixel to the finger surface point it sees (the paper's map m).
    #[command(allow_negative_numbers = true)]
    Unproject(sensor::UnprojectArgs),
    /// Map a point on (or inside) the finger, in mm, to its pixel.
    #[command(allow_negative_numbers = true)]
    Project(sensor::ProjectArgs),
    /// Render a tactile image: an object pressed into the finger, or the empty finger.
    ///
    /// Examples:
    ///   geltip render --sensor paper --object sphere --at rotation=45 --depth 1 -o sphere.png --labels sphere.json
    ///   geltip render --sensor paper --reference -o ref.png
    ///   geltip render --sensor out/sensor.toml --object sphere --at rotation=45 --depth 1 --background empty.png -o on_real.png
    #[command(allow_negative_numbers = true, verbatim_doc_comment)]
    Render(render::RenderArgs),
    /// Find the contact in a tactile image and map it onto the finger.
    ///
    /// Example:
    ///   geltip localise --sensor paper --reference ref.png --method surface sphere.png
    #[command(verbatim_doc_comment)]
    Localise(localise::LocaliseArgs),
    /// Run an experiment. `paper`: the paper's contact-localisation protocol (7 solids x 8
    /// taps), rendered, localised by every method, scored against the ground truth.
    ///
    /// Example:
    ///   geltip experiment paper --sensor paper --out out/experiment
    #[command(verbatim_doc_comment)]
    Experiment(jobs::ExperimentArgs),
    /// Render a labelled synthetic dataset: random contacts anywhere the lens can see, drawn
    /// from (seed, sample index) alone; resumable, shardable.
    ///
    /// Examples:
    ///   geltip dataset --sensor paper --count 10000 --seed 1 --out data/train
    ///   geltip dataset --sensor paper --count 10000 --seed 1 --shard 0/4 --out data/s0
    ///   geltip dataset --merge data/train data/s0 data/s1 data/s2 data/s3
    #[command(verbatim_doc_comment)]
    Dataset(dataset::DatasetArgs),
    /// Score a contact detector against the labels: a predictions file, a program reading
    /// frames on its stdin, or a built-in localiser, on a dataset or a suite (exact labels)
    /// or a real sensor's labelled frames (pixels, azimuths, regions, "no contact").
    ///
    /// Examples:
    ///   geltip evaluate --dataset data/test --predictions mine.jsonl --out eval/mine
    ///   geltip evaluate --real real/labels.json --sensor allsight --method change --out eval/real
    ///   geltip evaluate --dataset data/test --detector "python3 detect.py" --out eval/mine
    ///   geltip evaluate --suite paper --sensor paper --method surface --out eval/surface --compare eval/mine
    #[command(verbatim_doc_comment)]
    Evaluate(evaluate::EvaluateArgs),
    /// Fit a sensor file to a real sensor's frames: the lens from the image circle, the LEDs,
    /// ambient light, paint, vignetting and the camera's colour response from an empty frame,
    /// the noise from several, the imprint's values from frames with known contacts.
    ///
    /// Examples:
    ///   geltip calibrate --sensor paper --empty empty.png --out calibrated
    ///   geltip calibrate --sensor allsight --empty s1_ref_frame.jpg --out calibrated
    #[command(verbatim_doc_comment)]
    Calibrate(calibrate::CalibrateArgs),
    /// Fit the imprint's look (the gel's blend, drape, bulge and shading, and the indenter's
    /// radius) to a real sensor's labelled contact frames, and score it on other frames of
    /// the set inside a window round each imprint.
    ///
    /// Example:
    ///   geltip imprint --sensor allsight --real labels.json --out imprint
    #[command(verbatim_doc_comment)]
    Imprint(imprint::ImprintArgs),
    /// Preview sensor designs before building them: what the camera sees, the resolution
    /// down the finger, a picture per design, and a lens sweep.
    ///
    /// Example:
    ///   geltip preview --sensors paper,webcam70,tube13,tube21 --out out/preview
    #[command(verbatim_doc_comment)]
    Preview(jobs::PreviewArgs),
    /// Where the detectors fail: a sweep of contacts over everything the lens sees and press
    /// depths up to the shell thickness, with and without sensor noise.
    ///
    /// Example:
    ///   geltip stability --sensor paper --out out/stability
    #[command(verbatim_doc_comment)]
    Stability(jobs::StabilityArgs),
    /// Speed against accuracy for the renderer's knobs (heightfield texels, ray steps, image
    /// size, mesh SDF voxel size): frames/s, image error and localisation error, Pareto chart.
    ///
    /// Example:
    ///   geltip tradeoff --sensor paper --out out/tradeoff
    #[command(verbatim_doc_comment)]
    Tradeoff(jobs::TradeoffArgs),
    /// Write the seven built-in solids as OBJ meshes (the files in assets/objects/).
    Objects(jobs::ObjectsArgs),
}

/// Names a library error about one of a job's options by the flag that gives it: the
/// option's own name as a flag (`depth_range` -> `--depth-range`), or the flag `renamed`
/// pairs it with (`("designs", "--sensors")`). Other errors stay as they are.
pub fn under_flags<'a>(
    renamed: &'a [(&'a str, &'a str)],
) -> impl Fn(GeltipError) -> anyhow::Error + 'a {
    move |e| match e {
        GeltipError::InvalidOption {
            option,
            value,
            reason,
        } => {
            let flag = match renamed.iter().find(|(name, _)| *name == option) {
                Some((_, flag)) => flag.to_string(),
                None => format!("--{}", option.replace('_', "-")),
            };
            GeltipError::InvalidOption {
                option: flag,
                value,
                reason,
            }
            .into()
        }
        other => other.into(),
    }
}
