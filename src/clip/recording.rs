//! What a tracker's recording says about itself besides its positions: the unit they are in,
//! the number of its first frame, and whether its data lie in a plane (a single camera's 2D
//! midlines). The files are read in `crate::engine::input::recording`.
//!
//! ## Planar recordings
//! A recording is planar when its positions have two coordinates (CSV `frame,node,x_um,y_um`,
//! NPY `frames × nodes × 2`: placed at z = 0), or three of which one is the same number in every
//! frame and node (a tracker that writes z = 0). Such data say nothing about the rotation of the
//! cross-section about the centreline: the twist κ3 and the roll of (d1, d2) about d3 are not
//! observable, and the position noise has two components, not three (`crate::recorded::fit`).
use nalgebra::Vector3;

/// Unit of a recording's positions (`clip.unit`, or the suffix of a CSV header `x_um`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LengthUnit {
    /// metres (`m`)
    #[default]
    Metre,
    /// millimetres (`mm`)
    Millimetre,
    /// micrometres (`um`, `µm`, `μm`)
    Micrometre,
    /// camera pixels (`px`): metres per pixel from `clip.scale_m_per_px`
    Pixel,
}

impl LengthUnit {
    /// The unit of a name: `m`, `mm`, `um` (or `µm`, `μm`, `micron`, `microns`), `px`.
    pub fn parse(name: &str) -> Option<LengthUnit> {
        Some(match name {
            "m" => LengthUnit::Metre,
            "mm" => LengthUnit::Millimetre,
            "um" | "µm" | "μm" | "micron" | "microns" => LengthUnit::Micrometre,
            "px" => LengthUnit::Pixel,
            _ => return None,
        })
    }

    /// The short name (`m`, `mm`, `um`, `px`).
    pub fn name(self) -> &'static str {
        match self {
            LengthUnit::Metre => "m",
            LengthUnit::Millimetre => "mm",
            LengthUnit::Micrometre => "um",
            LengthUnit::Pixel => "px",
        }
    }

    /// Metres per unit; a pixel's is `m_per_px` (`None` where it is not given).
    pub fn metres(self, m_per_px: Option<f64>) -> Option<f64> {
        match self {
            LengthUnit::Metre => Some(1.0),
            LengthUnit::Millimetre => Some(1e-3),
            LengthUnit::Micrometre => Some(1e-6),
            LengthUnit::Pixel => m_per_px,
        }
    }
}

/// How a recording's positions are turned into metres: the case's `clip.unit` (`None`: as the
/// file says, metres where it says nothing) and `clip.scale_m_per_px`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UnitSpec {
    pub unit: Option<LengthUnit>,
    /// metres per pixel [m]
    pub m_per_px: Option<f64>,
}

/// What a recording says about itself (module doc).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordingInfo {
    /// the file's number of the clip's frame 0 (CSV: the smallest frame number; WCON: the time
    /// over the frame interval; NPY and kymograms: 0)
    pub first_frame: usize,
    /// the unit the positions were read in
    pub unit: LengthUnit,
    /// unit normal of the plane of a planar recording (module doc), in space coordinates
    /// (after `clip.orientation`); `None`: 3D data
    pub plane_normal: Option<Vector3<f64>>,
}

/// The coordinate axis on which every finite position of `frames` has the same value, if one
/// axis does (z before y before x): the normal of a planar recording written with three
/// columns. `None` if no axis is constant or nothing is finite.
pub fn constant_axis(frames: &[Vec<Vector3<f64>>]) -> Option<usize> {
    let mut axes = ConstantAxes::default();
    frames.iter().for_each(|f| axes.push(f));
    axes.axis()
}

/// [`constant_axis`] of frames that arrive one at a time (a recording read from its file a
/// frame at a time): the first finite position and, per axis, whether every finite position
/// since has had its value.
#[derive(Clone, Copy, Debug, Default)]
pub struct ConstantAxes {
    first: Option<Vector3<f64>>,
    varies: [bool; 3],
}

impl ConstantAxes {
    /// Take the positions of one more frame.
    pub fn push(&mut self, frame: &[Vector3<f64>]) {
        for p in frame.iter().filter(|p| p.iter().all(|v| v.is_finite())) {
            let first = *self.first.get_or_insert(*p);
            for k in 0..3 {
                self.varies[k] |= p[k] != first[k];
            }
        }
    }

    /// The constant axis of the frames taken ([`constant_axis`]).
    pub fn axis(&self) -> Option<usize> {
        self.first?;
        [2, 1, 0].into_iter().find(|&k| !self.varies[k])
    }
}

pub use crate::recorded::fit::plane_basis;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_convert_to_metres() {
        for (name, m) in [("m", 1.0), ("mm", 1e-3), ("um", 1e-6), ("µm", 1e-6), ("μm", 1e-6)] {
            assert_eq!(LengthUnit::parse(name).and_then(|u| u.metres(None)), Some(m), "{name}");
        }
        assert_eq!(LengthUnit::parse("px").and_then(|u| u.metres(Some(2.5e-6))), Some(2.5e-6));
        assert_eq!(LengthUnit::Pixel.metres(None), None);
        assert_eq!(LengthUnit::parse("inch"), None);
    }

    #[test]
    fn a_constant_axis_is_found_and_the_plane_basis_is_right_handed() {
        let f = vec![vec![Vector3::new(1.0, 2.0, 0.0), Vector3::new(3.0, -1.0, 0.0), Vector3::new(f64::NAN, 0.0, 7.0)]];
        assert_eq!(constant_axis(&f), Some(2));
        let g = vec![vec![Vector3::new(1.0, 5.0, 0.0), Vector3::new(3.0, 5.0, 1.0)]];
        assert_eq!(constant_axis(&g), Some(1));
        let h = vec![vec![Vector3::new(1.0, 5.0, 0.0), Vector3::new(3.0, 4.0, 1.0)]];
        assert_eq!(constant_axis(&h), None);
        assert_eq!(plane_basis(&Vector3::z()), (Vector3::x(), Vector3::y()));
        let n = Vector3::new(0.3, -0.5, 0.8).normalize();
        let (a, b) = plane_basis(&n);
        assert!(a.dot(&n).abs() < 1e-15 && b.dot(&n).abs() < 1e-15 && (a.cross(&b) - n).norm() < 1e-15);
    }
}
