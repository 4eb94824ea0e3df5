//! `[rod]`: the mesh, where its length comes from (`rod.length_m = "from_data"`), and the
//! slenderness that double precision solves.
use super::super::raw::{RawRod, Scalar};
use super::super::{Analysis, ClipKind, DataSource, InverseSettings, RodLength, FROM_DATA, FROM_DATA_PLACEHOLDER_M};
use super::{CaseError, Validator, MAX_ELEMENTS};
use crate::model::material::CrossSection;
use crate::model::mesh::Mesh;

impl Validator<'_> {
    /// `[rod]`: the mesh, and where its length comes from. `length_m = "from_data"` leaves the
    /// length to the recording ([`RodLength::FromData`]); until it is read, the mesh has the
    /// placeholder length [`FROM_DATA_PLACEHOLDER_M`].
    pub(super) fn mesh(&self, rod: &RawRod) -> Result<(Mesh, RodLength), CaseError> {
        let (length, source) = match &rod.length_m {
            Scalar::Text(t) if t.trim() == FROM_DATA => (FROM_DATA_PLACEHOLDER_M, RodLength::FromData(None)),
            v => (self.positive("rod.length_m", v)?, RodLength::Given),
        };
        if rod.elements < 2 {
            return Err(self.err("rod.elements", format!("need at least 2 elements, got {}", rod.elements)));
        }
        if rod.elements > MAX_ELEMENTS {
            return Err(self.err("rod.elements", format!("at most {MAX_ELEMENTS} elements, got {}", rod.elements)));
        }
        Ok((Mesh::new(length, rod.elements), source))
    }

    /// `rod.length_m = "from_data"` needs a recording to measure: an inverse case with a
    /// `[clip]` of `kind = "recording"`.
    pub(super) fn length_from_data(&self, rod_length: RodLength, analysis: &Analysis) -> Result<(), CaseError> {
        if rod_length == RodLength::Given {
            return Ok(());
        }
        let what = match analysis {
            Analysis::Inverse(InverseSettings { data: DataSource::Clip(c), .. }) => match c.kind {
                ClipKind::Recording => return Ok(()),
                ClipKind::Kymogram => "a kymogram clip (a kymogram is scaled to the rod length)",
                ClipKind::Roll3d(_) => "a roll_3d clip (it is generated at the rod length)",
            },
            Analysis::Inverse(_) => "an inverse case with [data] (a forward solve on the rod)",
            Analysis::Static(_) => "a static case",
            Analysis::Dynamic(_) => "a dynamic case",
        };
        Err(self.err(
            "rod.length_m",
            format!(
                "\"{FROM_DATA}\" estimates the body length from a recording: only for an inverse case with [clip] kind = \"recording\", but this is {what}; give the length in metres"
            ),
        ))
    }

    /// The rod's geometry within what double precision solves: the cross section's area and
    /// second moments finite and > 0, and the slenderness `L / r_g` (`r_g = √(min(I1, I2)/A)`,
    /// the radius of gyration) at most `1/√ε` ≈ 6.7e7. The stretching stiffness `EA` exceeds
    /// the bending stiffness `EI/L²` by `(L/r_g)²`; beyond `1/ε` one matrix cannot hold both, and
    /// the tangent is singular in double precision (a length in the wrong unit, `1e200`, …).
    pub(super) fn slenderness(&self, mesh: &Mesh, section: &CrossSection) -> Result<(), CaseError> {
        let (area, m) = (section.area_m2(), section.second_moments_m4());
        let key = match section {
            CrossSection::Circle { .. } => "cross_section.radius_m",
            CrossSection::Rectangle { .. } => "cross_section.width_m",
        };
        if !(area.is_finite() && area > 0.0 && m.iter().all(|v| v.is_finite() && *v > 0.0)) {
            return Err(self.err(
                key,
                format!(
                    "the cross section's area {area:e} m² and second moments {:e}, {:e} m⁴ must be finite and > 0 in double precision",
                    m[0], m[1]
                ),
            ));
        }
        let r_g = (m[0].min(m[1]) / area).sqrt();
        let (slenderness, max) = (mesh.length_m / r_g, f64::EPSILON.sqrt().recip());
        if slenderness.is_nan() || slenderness > max {
            return Err(self.err(
                "rod.length_m",
                format!(
                    "{:e} m is {slenderness:.2e} times the cross section's radius of gyration ({r_g:e} m); above {max:.1e} (1/√ε) the stretching stiffness EA exceeds the bending stiffness EI/L² by more than 1/ε, and the discrete equations cannot be solved in double precision: check the units of the length and of the cross section",
                    mesh.length_m
                ),
            ));
        }
        Ok(())
    }
}
