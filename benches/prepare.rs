//! `cargo bench --bench prepare`: the CPU's share of a contact frame, before the GPU runs:
//! the pose (first-touch search) and the footprint scan, per contact, for the paper's 56
//! taps (held at their places, and as rigid poses with approaches) and for random dataset contacts (`geltip dataset`'s draws, seed 1) per object. A
//! bench binary printing a table, not a timed test.

use geltip::jobs::{dataset, experiment};
use geltip::object::{Object, Solid};
use geltip::render::{contact, elastomer, HeightfieldGrid, Hold, Press};
use geltip::sensor::Sensor;
use std::sync::Arc;
use std::time::Instant;

/// Mean pose and footprint milliseconds over `list`.
fn time(sensor: &Sensor, list: &[Press]) -> anyhow::Result<(f64, f64)> {
    let grid = HeightfieldGrid::for_sensor(sensor);
    let kernel = elastomer::Kernel::for_config(&sensor.config, &grid);
    let (mut pose_s, mut footprint_s) = (0.0, 0.0);
    for press in list {
        let t0 = Instant::now();
        let pose = press.pose(sensor)?;
        let t1 = Instant::now();
        let _ = contact::footprint(sensor, &grid, &pose, &press.object, kernel.reach_mm);
        pose_s += (t1 - t0).as_secs_f64();
        footprint_s += t1.elapsed().as_secs_f64();
    }
    let n = list.len().max(1) as f64;
    Ok((1e3 * pose_s / n, 1e3 * footprint_s / n))
}

fn main() -> anyhow::Result<()> {
    geltip::memory::keep_freed_memory();
    let sensor = Sensor::preset("paper")?;
    println!("geltip prepare benchmark: sensor paper, per contact (ms), rayon over the cores");
    println!("| contacts | n | pose ms | footprint ms |");
    println!("|---|---|---|---|");
    let taps = experiment::all_taps(&Default::default());
    let (p, f) = time(&sensor, &taps)?;
    println!("| the paper's taps | {} | {p:.3} | {f:.3} |", taps.len());
    // The same taps as rigid poses pressing along the normal (as geltip.mujoco holds a
    // physics engine's geoms): their first touch is searched along the whole approach.
    let posed = taps
        .iter()
        .map(|t| {
            let pose = t.pose(&sensor)?;
            Ok(Press {
                object: t.object.clone(),
                hold: Hold::Pose {
                    world_from_object: pose.world_from_object,
                    origin: pose.origin,
                    approach: Some(-pose.normal),
                },
            })
        })
        .collect::<geltip::Result<Vec<_>>>()?;
    let (p, f) = time(&sensor, &posed)?;
    println!(
        "| the paper's taps as rigid poses with approaches | {} | {p:.3} | {f:.3} |",
        posed.len()
    );
    let depths = dataset::default_depth_range(sensor.finger.shell_thickness);
    for solid in Solid::ALL {
        let objects = vec![Arc::new(Object::Solid(solid))];
        let list = (0..100)
            .map(|k| dataset::sample_contact(&sensor, &objects, depths, 1, k))
            .collect::<geltip::Result<Vec<_>>>()?;
        let (p, f) = time(&sensor, &list)?;
        println!(
            "| random {} | {} | {p:.3} | {f:.3} |",
            solid.name(),
            list.len()
        );
    }
    Ok(())
}
