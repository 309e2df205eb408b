//! Ordering slices (or frames) along the slice normal, z spacing, and the stack checks:
//! duplicate positions and missing slices.
use glam::{DMat3, DVec3};

/// Where each slice is and what to fall back on when positions are missing.
pub(super) struct StackInput<'a> {
    /// `"slice"` or `"frame"`, for messages.
    pub what: &'a str,
    /// A name for each slice in messages (file name or frame number).
    pub labels: Vec<String>,
    /// ImagePositionPatient of each slice.
    pub positions: Vec<Option<DVec3>>,
    /// InstanceNumber of each slice (used when positions are missing).
    pub instances: Vec<Option<i64>>,
    /// How the order without positions is described (`"InstanceNumber"`, `"frame order"`).
    pub fallback_order: &'a str,
    /// ImageOrientationPatient (row then column direction cosines).
    pub orientation: Option<[f64; 6]>,
    /// SpacingBetweenSlices.
    pub spacing_between: Option<f64>,
    /// SliceThickness.
    pub thickness: Option<f64>,
}

/// The ordered stack.
#[derive(Debug)]
pub(super) struct Stack {
    /// Input indices in increasing position along the normal.
    pub order: Vec<usize>,
    pub z_spacing: f64,
    pub origin: DVec3,
    /// Columns: the row direction (i), the column direction (j) of ImageOrientationPatient
    /// and the slice normal (k, the order of the stack); identity without an orientation.
    pub direction: DMat3,
    pub notes: Vec<String>,
}

/// Positions closer than this (mm) along the normal are duplicates.
const SAME_POSITION_MM: f64 = 1e-3;
/// A gap larger than this many median gaps means a missing slice.
const MISSING_GAP_RATIO: f64 = 1.5;

/// The slice normal: row cosines x column cosines (z when absent or degenerate).
fn normal(orientation: Option<[f64; 6]>, notes: &mut Vec<String>) -> DVec3 {
    let Some(o) = orientation else {
        return DVec3::Z;
    };
    let (r, c) = (DVec3::new(o[0], o[1], o[2]), DVec3::new(o[3], o[4], o[5]));
    let n = r.cross(c);
    if n.length() < 1e-6 {
        notes.push(format!(
            "ImageOrientationPatient {o:?} is degenerate; the slice normal was taken as z"
        ));
        return DVec3::Z;
    }
    n.normalize()
}

/// The direction matrix of the stack (DICOM PS3.3 C.7.6.2.1.1): i along the row cosines
/// (ImageOrientationPatient[0..3], the direction of increasing column index), j along the
/// column cosines ([3..6]), k along the slice normal `n`, in which the stack is ordered.
/// Identity without an orientation; a non-orthonormal one is noted and not applied.
fn direction(orientation: Option<[f64; 6]>, n: DVec3, notes: &mut Vec<String>) -> DMat3 {
    let Some(o) = orientation else {
        return DMat3::IDENTITY;
    };
    let (r, c) = (DVec3::new(o[0], o[1], o[2]), DVec3::new(o[3], o[4], o[5]));
    match volux_core::orientation::validate_direction(DMat3::from_cols(r, c, n)) {
        Ok(d) => d,
        Err(e) => {
            notes.push(format!(
                "ImageOrientationPatient {o:?} is not applied ({e}): the grid is axis-aligned \
                 in (column, row, slice) order"
            ));
            DMat3::IDENTITY
        }
    }
}

/// Orders the stack and derives the z spacing; `Err` names a duplicate or missing slice.
pub(super) fn stack(input: &StackInput) -> Result<Stack, String> {
    let mut notes = Vec::new();
    let n = normal(input.orientation, &mut notes);
    let direction = direction(input.orientation, n, &mut notes);
    let positions: Option<Vec<DVec3>> = input.positions.iter().copied().collect();
    let stack = match positions {
        Some(p) if !p.is_empty() => by_position(input, &p, n, notes)?,
        _ => by_instance(input, notes),
    };
    Ok(Stack { direction, ..stack })
}

/// Sorts by the projection of the positions on the normal and checks the gaps.
fn by_position(
    input: &StackInput,
    p: &[DVec3],
    n: DVec3,
    mut notes: Vec<String>,
) -> Result<Stack, String> {
    let what = input.what;
    let proj: Vec<f64> = p.iter().map(|v| v.dot(n)).collect();
    let mut order: Vec<usize> = (0..p.len()).collect();
    order.sort_by(|&a, &b| proj[a].total_cmp(&proj[b]));
    let sorted: Vec<f64> = order.iter().map(|&i| proj[i]).collect();
    let gaps: Vec<f64> = sorted.windows(2).map(|w| w[1] - w[0]).collect();
    if let Some(i) = gaps.iter().position(|g| *g < SAME_POSITION_MM) {
        return Err(format!(
            "{} and {} have the same position {:.4} mm along the slice normal \
             (duplicate {what}s?)",
            label(input, order[i]),
            label(input, order[i + 1]),
            sorted[i]
        ));
    }
    let origin = p[order[0]];
    let Some(median) = median(&gaps) else {
        let z = fallback_z(input, false, &mut notes);
        return Ok(Stack {
            direction: DMat3::IDENTITY,
            order,
            z_spacing: z,
            origin,
            notes,
        });
    };
    if let Some(i) = gaps.iter().position(|g| *g > MISSING_GAP_RATIO * median) {
        return Err(format!(
            "gap of {:.4} mm between {} at {:.4} mm and {} at {:.4} mm is {:.2} times the \
             median gap {median:.4} mm: a {what} is missing",
            gaps[i],
            label(input, order[i]),
            sorted[i],
            label(input, order[i + 1]),
            sorted[i + 1],
            gaps[i] / median
        ));
    }
    let (lo, hi) = gaps
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), g| (l.min(*g), h.max(*g)));
    if hi - lo > 1e-3 * median.max(1.0) {
        notes.push(format!(
            "{what} gaps range from {lo:.4} to {hi:.4} mm; the median {median:.4} mm is used"
        ));
    }
    Ok(Stack {
        direction: DMat3::IDENTITY,
        order,
        z_spacing: median,
        origin,
        notes,
    })
}

/// The label of slice `i`.
fn label(input: &StackInput, i: usize) -> String {
    input
        .labels
        .get(i)
        .cloned()
        .unwrap_or_else(|| format!("{} {}", input.what, i + 1))
}

/// Orders by InstanceNumber (then input order) when positions are missing.
fn by_instance(input: &StackInput, mut notes: Vec<String>) -> Stack {
    let len = input.positions.len();
    let mut order: Vec<usize> = (0..len).collect();
    order.sort_by_key(|&i| (input.instances[i].is_none(), input.instances[i], i));
    if len > 1 {
        let missing = input.positions.iter().filter(|p| p.is_none()).count();
        notes.push(format!(
            "ImagePositionPatient is missing on {missing} of {len} {}s: ordered by {}",
            input.what, input.fallback_order
        ));
    }
    let origin = order
        .first()
        .and_then(|&i| input.positions[i])
        .unwrap_or(DVec3::ZERO);
    let z = fallback_z(input, len > 1, &mut notes);
    Stack {
        direction: DMat3::IDENTITY,
        order,
        z_spacing: z,
        origin,
        notes,
    }
}

/// z spacing without positions: SpacingBetweenSlices, else SliceThickness, else 1.
fn fallback_z(input: &StackInput, note: bool, notes: &mut Vec<String>) -> f64 {
    let (z, source) = match (input.spacing_between, input.thickness) {
        (Some(s), _) => (s, "SpacingBetweenSlices"),
        (None, Some(t)) => (t, "SliceThickness"),
        (None, None) => (
            1.0,
            "a default of 1 (no SpacingBetweenSlices or SliceThickness)",
        ),
    };
    if note {
        notes.push(format!("z spacing {z} mm from {source}"));
    }
    z
}

/// The median of the values (`None` when empty).
fn median(v: &[f64]) -> Option<f64> {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    match s.len() {
        0 => None,
        l if l % 2 == 1 => s.get(m).copied(),
        _ => Some((s.get(m - 1)? + s.get(m)?) / 2.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(z: &[f64]) -> StackInput<'static> {
        StackInput {
            what: "slice",
            labels: Vec::new(),
            positions: z.iter().map(|&z| Some(DVec3::new(0.0, 0.0, z))).collect(),
            instances: vec![None; z.len()],
            fallback_order: "InstanceNumber",
            orientation: Some([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            spacing_between: None,
            thickness: None,
        }
    }

    #[test]
    fn sorts_by_position() {
        let s = stack(&input(&[12.0, 0.0, -12.0])).unwrap();
        assert_eq!(s.order, vec![2, 1, 0]);
        assert_eq!(s.z_spacing, 12.0);
        assert_eq!(s.origin.z, -12.0);
        assert!(s.notes.is_empty());
    }

    #[test]
    fn sagittal_orientation_gives_the_direction_and_origin() {
        // Rows along +y (P), columns along -z (I): the normal is -x (R).
        let mut i = input(&[0.0; 3]);
        i.orientation = Some([0.0, 1.0, 0.0, 0.0, 0.0, -1.0]);
        i.positions = [12.0, 0.0, -12.0]
            .iter()
            .map(|&x| Some(DVec3::new(x, -250.0, 250.0)))
            .collect();
        let s = stack(&i).unwrap();
        assert_eq!(s.order, vec![0, 1, 2], "increasing along -x");
        assert_eq!(s.origin, DVec3::new(12.0, -250.0, 250.0));
        assert_eq!(s.z_spacing, 12.0);
        assert_eq!(
            s.direction,
            DMat3::from_cols(DVec3::Y, -DVec3::Z, -DVec3::X)
        );
        assert_eq!(
            volux_core::orientation::orientation_code(&s.direction),
            "PIR"
        );
        assert!(s.notes.is_empty(), "{:?}", s.notes);
        // A sheared orientation is noted and not applied.
        i.orientation = Some([1.0, 0.0, 0.0, 0.1, 0.995, 0.0]);
        i.positions = [0.0, 1.0, 2.0]
            .iter()
            .map(|&z| Some(DVec3::new(0.0, 0.0, z)))
            .collect();
        let s = stack(&i).unwrap();
        assert_eq!(s.direction, DMat3::IDENTITY);
        assert!(
            s.notes.iter().any(|n| n.contains("not orthogonal")),
            "{:?}",
            s.notes
        );
    }

    #[test]
    fn duplicate_and_missing() {
        assert!(stack(&input(&[0.0, 1.0, 1.0, 2.0]))
            .unwrap_err()
            .contains("same position"));
        assert!(stack(&input(&[0.0, 1.0, 2.0, 4.0, 5.0]))
            .unwrap_err()
            .contains("missing"));
    }

    #[test]
    fn instance_fallback() {
        let mut i = input(&[0.0, 0.0]);
        i.positions = vec![None, None];
        i.instances = vec![Some(2), Some(1)];
        i.thickness = Some(3.0);
        let s = stack(&i).unwrap();
        assert_eq!(s.order, vec![1, 0]);
        assert_eq!(s.z_spacing, 3.0);
        assert_eq!(s.notes.len(), 2);
    }
}
