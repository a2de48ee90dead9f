//! A detector's results over a set, summed up: recall, false positives, errors in mm on the
//! finger and in pixels, precision against recall over confidence thresholds and the average
//! precision, and the same broken down by region, press depth and object.

use super::detections::Found;
use super::matching::SampleScore;
use super::truth::{depth_bin, SampleTruth, DEPTH_EDGES, REGIONS};
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// One frame: its labels, what the detector reported, and how that scored.
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    pub truth: SampleTruth,
    pub found: Vec<Found>,
    pub score: SampleScore,
}

/// Mean, median, 95th percentile and largest of a set of errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorStats {
    pub count: usize,
    pub mean: f64,
    pub median: f64,
    pub p95: f64,
    pub max: f64,
}

impl ErrorStats {
    /// The statistics of `values` (percentiles interpolated between order statistics);
    /// `None` when there are none.
    pub fn of(mut values: Vec<f64>) -> Option<ErrorStats> {
        if values.is_empty() {
            return None;
        }
        values.sort_by(f64::total_cmp);
        let n = values.len();
        let quantile = |q: f64| {
            let x = q * (n - 1) as f64;
            let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
            values[lo] + (values[hi] - values[lo]) * (x - lo as f64)
        };
        Some(ErrorStats {
            count: n,
            mean: values.iter().sum::<f64>() / n as f64,
            median: quantile(0.5),
            p95: quantile(0.95),
            max: values[n - 1],
        })
    }

    fn to_json(stats: &Option<ErrorStats>) -> Value {
        match stats {
            Some(s) => json!({"mean": s.mean, "median": s.median, "p95": s.p95, "max": s.max}),
            None => json!({"mean": null, "median": null, "p95": null, "max": null}),
        }
    }
}

/// Visible contacts of one kind (a region, a depth bin, an object) and how many were found.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    pub name: String,
    pub visible: usize,
    pub detected: usize,
    pub error_mm: Option<ErrorStats>,
}

impl Group {
    /// Detected over visible; `None` with nothing visible.
    pub fn recall(&self) -> Option<f64> {
        (self.visible > 0).then(|| self.detected as f64 / self.visible as f64)
    }

    fn to_json(&self) -> Value {
        json!({
            "visible": self.visible,
            "detected": self.detected,
            "recall": self.recall(),
            "error_mm": ErrorStats::to_json(&self.error_mm),
        })
    }
}

/// A point of the precision-recall curve: what a detector scores keeping only the
/// detections of at least `threshold` confidence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrPoint {
    pub threshold: f64,
    pub precision: f64,
    pub recall: f64,
}

/// A detector's results over a set.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    pub detector: String,
    pub samples: usize,
    /// Contacts the lens sees, and those a detection matched.
    pub visible: usize,
    pub detected: usize,
    /// Frames with no contact at all.
    pub empty_frames: usize,
    pub false_positives: usize,
    /// False positives on the empty frames.
    pub false_positives_on_empty: usize,
    /// Detections of contacts the lens cannot see (neither right nor wrong).
    pub ignored: usize,
    pub error_mm: Option<ErrorStats>,
    pub error_px: Option<ErrorStats>,
    /// Area under the interpolated precision-recall curve; `None` with nothing visible.
    pub average_precision: Option<f64>,
    pub precision_recall: Vec<PrPoint>,
    pub by_region: Vec<Group>,
    pub by_depth: Vec<Group>,
    pub by_object: Vec<Group>,
}

/// Most points a summary keeps of the precision-recall curve (evenly spread in rank).
const PR_POINTS: usize = 200;

impl Summary {
    /// The summary of `detector`'s scored frames.
    pub fn of(detector: &str, frames: &[Scored]) -> Summary {
        let visible = frames.iter().map(|f| f.truth.visible()).sum();
        let detected = frames.iter().map(|f| f.score.matches.len()).sum();
        let matches = || frames.iter().flat_map(|f| f.score.matches.iter());
        let (average_precision, precision_recall) = precision_recall(frames, visible);
        Summary {
            detector: detector.to_string(),
            samples: frames.len(),
            visible,
            detected,
            empty_frames: frames
                .iter()
                .filter(|f| f.truth.contacts.is_empty())
                .count(),
            false_positives: frames.iter().map(|f| f.score.false_positives.len()).sum(),
            false_positives_on_empty: frames
                .iter()
                .filter(|f| f.truth.contacts.is_empty())
                .map(|f| f.score.false_positives.len())
                .sum(),
            ignored: frames.iter().map(|f| f.score.ignored.len()).sum(),
            error_mm: ErrorStats::of(matches().map(|m| m.error_mm).collect()),
            error_px: ErrorStats::of(matches().filter_map(|m| m.error_px).collect()),
            average_precision,
            precision_recall,
            by_region: groups(frames, |c| c.region.to_string(), &REGIONS.map(String::from)),
            by_depth: groups(frames, |c| depth_bin(c.depth_mm), &depth_bins()),
            by_object: groups(frames, |c| c.object.clone(), &[]),
        }
    }

    /// Detected over visible; `None` with nothing visible.
    pub fn recall(&self) -> Option<f64> {
        (self.visible > 0).then(|| self.detected as f64 / self.visible as f64)
    }

    /// `summary.json`'s object.
    pub fn to_json(&self) -> Value {
        let groups = |gs: &[Group]| -> Value {
            Value::Object(gs.iter().map(|g| (g.name.clone(), g.to_json())).collect())
        };
        json!({
            "detector": self.detector,
            "samples": self.samples,
            "visible": self.visible,
            "detected": self.detected,
            "recall": self.recall(),
            "empty_frames": self.empty_frames,
            "false_positives": self.false_positives,
            "false_positives_on_empty_frames": self.false_positives_on_empty,
            "ignored": self.ignored,
            "error_mm": ErrorStats::to_json(&self.error_mm),
            "error_px": ErrorStats::to_json(&self.error_px),
            "average_precision": self.average_precision,
            "by_region": groups(&self.by_region),
            "by_depth": groups(&self.by_depth),
            "by_object": groups(&self.by_object),
            "precision_recall": self.precision_recall.iter()
                .map(|p| [p.threshold, p.precision, p.recall]).collect::<Vec<_>>(),
        })
    }
}

/// The depth bins' labels, in order.
pub fn depth_bins() -> Vec<String> {
    DEPTH_EDGES.iter().map(|&d| depth_bin(d)).collect()
}

/// The visible contacts grouped by `key`: the groups named in `order` first (those with
/// contacts), then any others by name.
fn groups(
    frames: &[Scored],
    key: impl Fn(&super::truth::LabelledContact) -> String,
    order: &[String],
) -> Vec<Group> {
    let mut by: BTreeMap<String, (usize, Vec<f64>)> = BTreeMap::new();
    for f in frames {
        for (i, c) in f.truth.contacts.iter().enumerate() {
            if !c.visible {
                continue;
            }
            let entry = by.entry(key(c)).or_default();
            entry.0 += 1;
            if let Some(m) = f.score.matches.iter().find(|m| m.contact == i) {
                entry.1.push(m.error_mm);
            }
        }
    }
    let mut names: Vec<String> = order
        .iter()
        .filter(|n| by.contains_key(*n))
        .cloned()
        .collect();
    names.extend(by.keys().filter(|k| !order.contains(k)).cloned());
    names
        .into_iter()
        .map(|name| {
            let (visible, errors) = by.remove(&name).unwrap_or_default();
            Group {
                name,
                visible,
                detected: errors.len(),
                error_mm: ErrorStats::of(errors),
            }
        })
        .collect()
}

/// Average precision (all-point interpolation) and the precision-recall curve over the
/// detections' confidences. A detection that matched is a true positive at every threshold
/// that keeps it; ignored detections count as neither.
fn precision_recall(frames: &[Scored], visible: usize) -> (Option<f64>, Vec<PrPoint>) {
    let mut ranked: Vec<(f64, bool)> = Vec::new();
    for f in frames {
        for m in &f.score.matches {
            ranked.push((f.found[m.detection].confidence, true));
        }
        for &j in &f.score.false_positives {
            ranked.push((f.found[j].confidence, false));
        }
    }
    if visible == 0 {
        return (None, Vec::new());
    }
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
    // One point per distinct confidence: a threshold keeps every detection at or above it.
    let mut curve = Vec::new();
    let (mut tp, mut fp) = (0usize, 0usize);
    for (k, &(confidence, hit)) in ranked.iter().enumerate() {
        if hit {
            tp += 1;
        } else {
            fp += 1;
        }
        if ranked.get(k + 1).is_none_or(|next| next.0 != confidence) {
            curve.push(PrPoint {
                threshold: confidence,
                precision: tp as f64 / (tp + fp) as f64,
                recall: tp as f64 / visible as f64,
            });
        }
    }
    // Area under the curve made monotone from the right (each recall's best precision at
    // that recall or more).
    let mut ap = 0.0;
    let mut best = 0.0f64;
    let mut envelope = vec![0.0; curve.len()];
    for (k, p) in curve.iter().enumerate().rev() {
        best = best.max(p.precision);
        envelope[k] = best;
    }
    let mut last_recall = 0.0;
    for (p, precision) in curve.iter().zip(&envelope) {
        ap += (p.recall - last_recall) * precision;
        last_recall = p.recall;
    }
    (Some(ap), thin(curve))
}

/// At most [`PR_POINTS`] of the curve, evenly spread, the last always kept.
fn thin(curve: Vec<PrPoint>) -> Vec<PrPoint> {
    if curve.len() <= PR_POINTS {
        return curve;
    }
    let n = curve.len();
    (0..PR_POINTS)
        .map(|k| curve[(k * (n - 1)) / (PR_POINTS - 1)])
        .collect()
}

/// The groups of `key` in any summary: those in `order` first, then the others by name.
pub(super) fn group_names(summaries: &[Value], key: &str, order: &[String]) -> Vec<String> {
    let mut all: Vec<String> = Vec::new();
    for s in summaries {
        if let Some(m) = s[key].as_object() {
            for k in m.keys() {
                if !all.contains(k) {
                    all.push(k.clone());
                }
            }
        }
    }
    let mut names: Vec<String> = order.iter().filter(|n| all.contains(n)).cloned().collect();
    let mut rest: Vec<String> = all.into_iter().filter(|n| !order.contains(n)).collect();
    rest.sort();
    names.extend(rest);
    names
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluate::matching::Match;
    use crate::evaluate::truth::LabelledContact;
    use glam::DVec3;

    fn frame(contacts: usize, hits: &[(f64, f64)], misses: &[f64]) -> Scored {
        let contact = LabelledContact {
            target: DVec3::Z,
            pixel: None,
            visible: true,
            object: "cone".into(),
            depth_mm: 0.5,
            s_mm: 1.0,
            azimuth_deg: 0.0,
            region: "tip",
        };
        let mut found = Vec::new();
        let mut score = SampleScore::default();
        for (k, &(confidence, error)) in hits.iter().enumerate() {
            found.push(Found {
                point: Some(DVec3::Z),
                pixel: None,
                confidence,
            });
            score.matches.push(Match {
                contact: k,
                detection: k,
                error_mm: error,
                error_px: None,
            });
        }
        for &confidence in misses {
            score.false_positives.push(found.len());
            found.push(Found {
                point: Some(DVec3::Z),
                pixel: None,
                confidence,
            });
        }
        score.missed = (hits.len()..contacts).collect();
        Scored {
            truth: SampleTruth {
                index: 0,
                contacts: vec![contact; contacts],
            },
            found,
            score,
        }
    }

    #[test]
    fn error_statistics_interpolate_percentiles() {
        let s = ErrorStats::of((1..=101).map(f64::from).collect()).unwrap();
        assert_eq!((s.mean, s.median, s.p95, s.max), (51.0, 51.0, 96.0, 101.0));
        let s = ErrorStats::of(vec![2.0, 1.0]).unwrap();
        assert_eq!((s.median, s.p95), (1.5, 1.95));
        assert!(ErrorStats::of(vec![]).is_none());
    }

    #[test]
    fn average_precision_of_ranked_hits() {
        // Ranked by confidence: hit, false, hit; two of three contacts found.
        let frames = [frame(3, &[(0.9, 0.1), (0.5, 0.3)], &[0.7])];
        let s = Summary::of("t", &frames);
        assert_eq!((s.visible, s.detected, s.false_positives), (3, 2, 1));
        // Curve: (r 1/3, p 1), (1/3, 1/2), (2/3, 2/3); interpolated AP = 1/3 * 1 + 1/3 * 2/3.
        assert!((s.average_precision.unwrap() - (1.0 / 3.0 + 2.0 / 9.0)).abs() < 1e-12);
        assert_eq!(s.precision_recall.len(), 3);
        assert_eq!(s.by_region[0].name, "tip");
        assert_eq!(s.by_depth[0].name, "0.4-0.7");
        assert!((s.error_mm.unwrap().mean - 0.2).abs() < 1e-12);
        // A perfect detector: AP 1; nothing visible: no AP.
        assert_eq!(
            Summary::of("t", &[frame(2, &[(1.0, 0.0), (1.0, 0.0)], &[])]).average_precision,
            Some(1.0)
        );
        assert_eq!(
            Summary::of("t", &[frame(0, &[], &[0.4])]).average_precision,
            None
        );
    }
}
