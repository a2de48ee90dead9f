//! Matching a frame's detections to its contacts, one to one: the Hungarian assignment on the
//! distance on the finger between each detection's point and each visible contact's target,
//! pairs farther apart than the gate not allowed. Unmatched visible contacts are misses;
//! unmatched detections are false positives, except those within the gate of a contact the
//! lens cannot see (its imprint may reach the image), which are ignored.

use super::detections::Found;
use super::truth::SampleTruth;

/// A detection matched to a contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Match {
    /// Index into the sample's contacts.
    pub contact: usize,
    /// Index into the frame's detections.
    pub detection: usize,
    /// Distance (mm) between the detection's point and the contact's target.
    pub error_mm: f64,
    /// Distance (px) between their pixels, where both have one.
    pub error_px: Option<f64>,
}

/// How one frame's detections scored.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SampleScore {
    pub matches: Vec<Match>,
    /// Visible contacts no detection matched.
    pub missed: Vec<usize>,
    /// Detections that matched no contact.
    pub false_positives: Vec<usize>,
    /// Unmatched detections within the gate of a contact the lens cannot see.
    pub ignored: Vec<usize>,
}

/// Cost of a pair beyond the gate: more than any sum of allowed distances, so the assignment
/// first matches as many allowed pairs as it can, then the closest.
const FORBIDDEN: f64 = 1e12;

/// Scores `found` against `truth`'s contacts; `gate_mm` `None` allows any distance.
pub fn score_sample(truth: &SampleTruth, found: &[Found], gate_mm: Option<f64>) -> SampleScore {
    let within = |d: f64| gate_mm.is_none_or(|g| d <= g);
    let rows: Vec<usize> = (0..truth.contacts.len())
        .filter(|&i| truth.contacts[i].visible)
        .collect();
    let cols: Vec<usize> = (0..found.len())
        .filter(|&j| found[j].point.is_some())
        .collect();
    let distance = |i: usize, j: usize| -> f64 {
        let p = found[j].point.unwrap_or_default();
        (p - truth.contacts[i].target).length()
    };
    let cost: Vec<Vec<f64>> = rows
        .iter()
        .map(|&i| {
            cols.iter()
                .map(|&j| {
                    let d = distance(i, j);
                    if within(d) {
                        d
                    } else {
                        FORBIDDEN
                    }
                })
                .collect()
        })
        .collect();
    let mut score = SampleScore::default();
    let mut matched_contact = vec![false; truth.contacts.len()];
    let mut matched_detection = vec![false; found.len()];
    for (r, c) in assign(&cost) {
        let (i, j) = (rows[r], cols[c]);
        let error_mm = distance(i, j);
        if !within(error_mm) {
            continue;
        }
        matched_contact[i] = true;
        matched_detection[j] = true;
        let error_px = match (found[j].pixel, truth.contacts[i].pixel) {
            (Some(a), Some(b)) => Some((a - b).length()),
            _ => None,
        };
        score.matches.push(Match {
            contact: i,
            detection: j,
            error_mm,
            error_px,
        });
    }
    score.matches.sort_by_key(|m| m.contact);
    score.missed = rows.into_iter().filter(|&i| !matched_contact[i]).collect();
    for j in (0..found.len()).filter(|&j| !matched_detection[j]) {
        let near_hidden = found[j].point.is_some()
            && truth
                .contacts
                .iter()
                .enumerate()
                .any(|(i, c)| !c.visible && within(distance(i, j)));
        if near_hidden {
            score.ignored.push(j);
        } else {
            score.false_positives.push(j);
        }
    }
    score
}

/// The assignment of rows to columns with the least total cost (Hungarian algorithm with
/// potentials, O(n² m)): `(row, column)` pairs, one per row of the smaller side.
pub fn assign(cost: &[Vec<f64>]) -> Vec<(usize, usize)> {
    let n = cost.len();
    let m = cost.first().map_or(0, Vec::len);
    if n == 0 || m == 0 {
        return Vec::new();
    }
    if n > m {
        let transposed: Vec<Vec<f64>> = (0..m)
            .map(|j| (0..n).map(|i| cost[i][j]).collect())
            .collect();
        return assign(&transposed)
            .into_iter()
            .map(|(j, i)| (i, j))
            .collect();
    }
    // Rows and columns are 1-based below; column 0 is the free row being placed.
    let mut u = vec![0.0; n + 1];
    let mut v = vec![0.0; m + 1];
    let mut row_of = vec![0usize; m + 1];
    let mut way = vec![0usize; m + 1];
    for i in 1..=n {
        row_of[0] = i;
        let mut j0 = 0;
        let mut min_to = vec![f64::INFINITY; m + 1];
        let mut used = vec![false; m + 1];
        loop {
            used[j0] = true;
            let i0 = row_of[j0];
            let mut delta = f64::INFINITY;
            let mut j1 = 0;
            for j in 1..=m {
                if used[j] {
                    continue;
                }
                let reduced = cost[i0 - 1][j - 1] - u[i0] - v[j];
                if reduced < min_to[j] {
                    min_to[j] = reduced;
                    way[j] = j0;
                }
                if min_to[j] < delta {
                    delta = min_to[j];
                    j1 = j;
                }
            }
            for j in 0..=m {
                if used[j] {
                    u[row_of[j]] += delta;
                    v[j] -= delta;
                } else {
                    min_to[j] -= delta;
                }
            }
            j0 = j1;
            if row_of[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            row_of[j0] = row_of[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    (1..=m)
        .filter(|&j| row_of[j] != 0)
        .map(|j| (row_of[j] - 1, j - 1))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluate::truth::LabelledContact;
    use glam::{DVec2, DVec3};

    /// Every assignment's cost, by brute force over permutations.
    fn best_by_brute_force(cost: &[Vec<f64>]) -> f64 {
        fn go(cost: &[Vec<f64>], row: usize, used: &mut Vec<bool>) -> f64 {
            if row == cost.len() {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for j in 0..cost[0].len() {
                if !used[j] {
                    used[j] = true;
                    best = best.min(cost[row][j] + go(cost, row + 1, used));
                    used[j] = false;
                }
            }
            best
        }
        go(cost, 0, &mut vec![false; cost[0].len()])
    }

    #[test]
    fn assignment_is_the_cheapest() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as f64 / (1u64 << 31) as f64
        };
        for (n, m) in [(1, 1), (2, 3), (3, 3), (4, 6), (5, 5), (3, 1)] {
            for _ in 0..20 {
                let cost: Vec<Vec<f64>> = (0..n)
                    .map(|_| (0..m).map(|_| next() * 10.0).collect())
                    .collect();
                let pairs = assign(&cost);
                assert_eq!(pairs.len(), n.min(m));
                let total: f64 = pairs.iter().map(|&(i, j)| cost[i][j]).sum();
                let (rows, cols): (Vec<_>, Vec<_>) = pairs.iter().cloned().unzip();
                assert!(rows.iter().collect::<std::collections::BTreeSet<_>>().len() == rows.len());
                assert!(cols.iter().collect::<std::collections::BTreeSet<_>>().len() == cols.len());
                let best = if n <= m {
                    best_by_brute_force(&cost)
                } else {
                    let t: Vec<Vec<f64>> = (0..m)
                        .map(|j| (0..n).map(|i| cost[i][j]).collect())
                        .collect();
                    best_by_brute_force(&t)
                };
                assert!((total - best).abs() < 1e-9, "{n}x{m}: {total} vs {best}");
            }
        }
    }

    fn contact(x: f64, visible: bool) -> LabelledContact {
        LabelledContact {
            target: DVec3::new(x, 0.0, 10.0),
            pixel: visible.then(|| DVec2::new(x * 10.0, 0.0)),
            visible,
            object: "sphere".into(),
            depth_mm: 1.0,
            s_mm: 5.0,
            azimuth_deg: 0.0,
            region: "hemisphere",
        }
    }

    fn at(x: f64) -> Found {
        Found {
            point: Some(DVec3::new(x, 0.0, 10.0)),
            pixel: Some(DVec2::new(x * 10.0, 0.0)),
            confidence: 1.0,
        }
    }

    #[test]
    fn swapped_detections_match_their_own_contacts() {
        let truth = SampleTruth {
            index: 0,
            contacts: vec![contact(0.0, true), contact(4.0, true)],
        };
        let s = score_sample(&truth, &[at(4.5), at(0.2)], Some(3.0));
        assert_eq!(s.matches.len(), 2);
        assert_eq!((s.matches[0].contact, s.matches[0].detection), (0, 1));
        assert_eq!((s.matches[1].contact, s.matches[1].detection), (1, 0));
        assert!((s.matches[0].error_mm - 0.2).abs() < 1e-12);
        assert!((s.matches[1].error_px.unwrap() - 5.0).abs() < 1e-9);
    }

    #[test]
    fn the_gate_turns_far_detections_into_a_miss_and_a_false_positive() {
        let truth = SampleTruth {
            index: 0,
            contacts: vec![contact(0.0, true)],
        };
        let s = score_sample(&truth, &[at(3.5)], Some(3.0));
        assert_eq!(
            (s.matches.len(), s.missed, s.false_positives),
            (0, vec![0], vec![0])
        );
        let s = score_sample(&truth, &[at(3.5)], None);
        assert_eq!(s.matches.len(), 1);
        // Two detections of one contact: the nearer matches, the other is a false positive.
        let s = score_sample(&truth, &[at(1.0), at(0.5)], Some(3.0));
        assert_eq!(
            (s.matches[0].detection, s.false_positives.clone()),
            (1, vec![0])
        );
    }

    #[test]
    fn detections_of_hidden_contacts_are_ignored_and_unplaced_ones_are_false_positives() {
        let truth = SampleTruth {
            index: 0,
            contacts: vec![contact(0.0, false)],
        };
        let unplaced = Found {
            point: None,
            pixel: Some(DVec2::ZERO),
            confidence: 1.0,
        };
        let s = score_sample(&truth, &[at(1.0), unplaced, at(9.0)], Some(3.0));
        assert!(s.matches.is_empty() && s.missed.is_empty());
        assert_eq!((s.ignored, s.false_positives), (vec![0], vec![1, 2]));
    }
}
