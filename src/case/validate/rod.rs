//! `[rod]`: the mesh, where its length comes from (`rod.length_m = "from_data"`), and the
//! slenderness that double precision solves.
use super::super::raw::{RawAnalysis, RawCase, RawMaterial, RawRod, RawSection, Scalar};
use super::super::{
    Analysis, ClipKind, DataSource, InverseSettings, RodLength, Section, FROM_DATA, FROM_DATA_PLACEHOLDER_M,
};
use super::{CaseError, Validator, MAX_ELEMENTS};
use crate::model::material::{CrossSection, Material, RodProperties, Stiffnesses};
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

    /// `rod.section_length_m`: the body length [m] the case's `[cross_section]` describes; where
    /// it is given and the rod's length is known, the section is scaled by `L / section_length_m`
    /// (a worm of another length is taken as geometrically similar: its radius in proportion to
    /// its length, so that its bending stiffness `E I` goes as `L⁴`). Until a length from the
    /// data is read, the section is left as it is.
    pub(super) fn scaled_section(
        &self,
        section: CrossSection,
        rod: &RawRod,
        mesh: &Mesh,
        length: RodLength,
    ) -> Result<CrossSection, CaseError> {
        let Some(v) = &rod.section_length_m else { return Ok(section) };
        let reference = self.positive("rod.section_length_m", v)?;
        if length != RodLength::Given {
            return Ok(section);
        }
        let k = mesh.length_m / reference;
        Ok(match section {
            CrossSection::Circle { radius_m } => CrossSection::Circle { radius_m: radius_m * k },
            CrossSection::Rectangle { width_m, height_m } => {
                CrossSection::Rectangle { width_m: width_m * k, height_m: height_m * k }
            }
        })
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

    /// `[cross_section]` and `[material]`: the section, the material (absent for a section given
    /// by its stiffnesses, D24), the coefficients of the model and whether the inertias were
    /// given (a dynamic analysis requires them).
    pub(super) fn section_and_material(
        &self,
        raw: &RawCase,
        kind: RawAnalysis,
        mesh: &Mesh,
        rod_length: RodLength,
    ) -> Result<(Section, Option<Material>, RodProperties, bool), CaseError> {
        match (&raw.cross_section, &raw.material) {
            (RawSection::Stiffness { .. }, Some(_)) => Err(self.err(
                "material",
                "not used with cross_section.shape = \"stiffness\": the stiffnesses and inertias are given there (D24)",
            )),
            (RawSection::Stiffness { .. }, None) => {
                let s = self.stiffnesses(&raw.cross_section, kind)?;
                let given = s.rho_a_kg_per_m.is_some() && s.rho_i_kg_m.is_some();
                Ok((Section::Stiffness(s), None, RodProperties::from_stiffnesses(&s), given))
            }
            (_, None) => Err(self.err(
                "material",
                "required with a circle or rectangle section (or give cross_section.shape = \"stiffness\" with the stiffnesses)",
            )),
            (shape, Some(m)) => {
                let material = self.material(m, kind)?;
                let section = self.scaled_section(self.shape(shape)?, &raw.rod, mesh, rod_length)?;
                let props = RodProperties::new(&material, &section);
                Ok((Section::Shape(section), Some(material), props, m.density_kg_m3.is_some()))
            }
        }
    }

    /// `[material]`; the density is required by a dynamic analysis only.
    fn material(&self, m: &RawMaterial, kind: RawAnalysis) -> Result<Material, CaseError> {
        let density = match (&m.density_kg_m3, kind) {
            (Some(d), _) => self.positive("material.density_kg_m3", d)?,
            (None, RawAnalysis::Static | RawAnalysis::Inverse) => 1.0,
            (None, RawAnalysis::Dynamic) => {
                return Err(self.err("material.density_kg_m3", "required for a dynamic analysis"))
            }
        };
        Ok(Material {
            young_modulus_pa: self.positive("material.young_modulus_pa", &m.young_modulus_pa)?,
            shear_modulus_pa: self.positive("material.shear_modulus_pa", &m.shear_modulus_pa)?,
            density_kg_m3: density,
            shear_correction: self.positive("material.shear_correction", &m.shear_correction)?,
        })
    }

    /// A circle or rectangle `[cross_section]`.
    fn shape(&self, s: &RawSection) -> Result<CrossSection, CaseError> {
        Ok(match s {
            RawSection::Circle { radius_m } => {
                CrossSection::Circle { radius_m: self.positive("cross_section.radius_m", radius_m)? }
            }
            RawSection::Rectangle { width_m, height_m } => CrossSection::Rectangle {
                width_m: self.positive("cross_section.width_m", width_m)?,
                height_m: self.positive("cross_section.height_m", height_m)?,
            },
            RawSection::Stiffness { .. } => unreachable!("a stiffness section is not a shape (section_and_material)"),
        })
    }

    /// `shape = "stiffness"` (D24): every stiffness > 0; the inertias all or none, required by a
    /// dynamic analysis.
    fn stiffnesses(&self, s: &RawSection, kind: RawAnalysis) -> Result<Stiffnesses, CaseError> {
        let RawSection::Stiffness {
            ea_n,
            ga1_n,
            ga2_n,
            ei1_nm2,
            ei2_nm2,
            gj_nm2,
            rho_a_kg_per_m,
            rho_i1_kg_m,
            rho_i2_kg_m,
            rho_j_kg_m,
        } = s
        else {
            unreachable!("called for a stiffness section")
        };
        let p = |k: &str, v: &Scalar| self.positive(&format!("cross_section.{k}"), v);
        let rho_a = rho_a_kg_per_m.as_ref().map(|v| p("rho_a_kg_per_m", v)).transpose()?;
        let inertia = [("rho_i1_kg_m", rho_i1_kg_m), ("rho_i2_kg_m", rho_i2_kg_m), ("rho_j_kg_m", rho_j_kg_m)];
        let given: Vec<f64> =
            inertia.iter().filter_map(|(k, v)| v.as_ref().map(|v| p(k, v))).collect::<Result<_, _>>()?;
        let rho_i = match given.len() {
            0 => None,
            3 => Some([given[0], given[1], given[2]]),
            _ => {
                let missing = inertia.iter().find(|(_, v)| v.is_none()).map(|(k, _)| *k).unwrap_or("rho_j_kg_m");
                return Err(self.err(&format!("cross_section.{missing}"), "give all three rotary inertias or none"));
            }
        };
        if kind == RawAnalysis::Dynamic {
            if rho_a.is_none() {
                return Err(self.err("cross_section.rho_a_kg_per_m", "required for a dynamic analysis"));
            }
            if rho_i.is_none() {
                return Err(
                    self.err("cross_section.rho_i1_kg_m", "the rotary inertias are required for a dynamic analysis")
                );
            }
        }
        Ok(Stiffnesses {
            ea_n: p("ea_n", ea_n)?,
            ga_n: [p("ga1_n", ga1_n)?, p("ga2_n", ga2_n)?],
            ei_nm2: [p("ei1_nm2", ei1_nm2)?, p("ei2_nm2", ei2_nm2)?],
            gj_nm2: p("gj_nm2", gj_nm2)?,
            rho_a_kg_per_m: rho_a,
            rho_i_kg_m: rho_i,
        })
    }

    /// The rod's geometry within what double precision solves: the cross section's area and
    /// second moments finite and > 0, and the slenderness `L / r_g` (`r_g = √(min(I1, I2)/A)`,
    /// the radius of gyration) at most `1/√ε` ≈ 6.7e7. The stretching stiffness `EA` exceeds
    /// the bending stiffness `EI/L²` by `(L/r_g)²`; beyond `1/ε` one matrix cannot hold both, and
    /// the tangent is singular in double precision (a length in the wrong unit, `1e200`, …).
    pub(super) fn slenderness(&self, mesh: &Mesh, section: &Section) -> Result<(), CaseError> {
        let section = match section {
            Section::Shape(s) => s,
            Section::Stiffness(s) => {
                return self.slenderness_of(mesh, s.radius_of_gyration_m(), "cross_section.ei1_nm2")
            }
        };
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
        self.slenderness_of(mesh, (m[0].min(m[1]) / area).sqrt(), key)
    }

    /// `L / r_g` within `1/√ε` ([`Validator::slenderness`]).
    fn slenderness_of(&self, mesh: &Mesh, r_g: f64, key: &str) -> Result<(), CaseError> {
        let (slenderness, max) = (mesh.length_m / r_g, f64::EPSILON.sqrt().recip());
        if !(r_g.is_finite() && r_g > 0.0) {
            return Err(self.err(key, format!("the section's radius of gyration {r_g:e} m must be finite and > 0")));
        }
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
