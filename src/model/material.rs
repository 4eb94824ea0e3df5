//! Rod material and cross-section: the stiffness and inertia diagonals of eqs. (12), (15), (16),
//! (37)–(39), Remark 2 and §5.1. All quantities per unit reference length, SI units.
use nalgebra::Vector3;

/// Linear elastic, homogeneous material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Young's modulus E [Pa]
    pub young_modulus_pa: f64,
    /// Shear modulus G [Pa]
    pub shear_modulus_pa: f64,
    /// Density ρ [kg/m³]
    pub density_kg_m3: f64,
    /// Shear correction factor k of eq. (12) [-]
    pub shear_correction: f64,
}

/// Cross-section geometry in the reference configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CrossSection {
    /// Circle of radius r [m] (Remark 2).
    Circle { radius_m: f64 },
    /// Rectangle: width a along d1, height b along d2 [m] (§5.1).
    Rectangle { width_m: f64, height_m: f64 },
}

impl CrossSection {
    /// Area A0 [m²].
    pub fn area_m2(&self) -> f64 {
        match *self {
            CrossSection::Circle { radius_m } => std::f64::consts::PI * radius_m * radius_m,
            CrossSection::Rectangle { width_m, height_m } => width_m * height_m,
        }
    }

    /// Second moments of area `(∫η², ∫ξ², ∫(ξ²+η²))` [m⁴] with ξ along d1 and η along d2, eq. (16).
    /// For the circle these are `A²/4π, A²/4π, A²/2π` (Remark 2); for the rectangle the
    /// polar entry is `(a b³ + a³ b)/12` as written in §5.1.
    pub fn second_moments_m4(&self) -> Vector3<f64> {
        match *self {
            CrossSection::Circle { .. } => {
                let a = self.area_m2();
                let i = a * a / (4.0 * std::f64::consts::PI);
                Vector3::new(i, i, 2.0 * i)
            }
            CrossSection::Rectangle { width_m: a, height_m: b } => {
                let i1 = a * b.powi(3) / 12.0;
                let i2 = a.powi(3) * b / 12.0;
                Vector3::new(i1, i2, i1 + i2)
            }
        }
    }
}

/// A section given by its stiffnesses and inertias, as the rod literature states them (D24).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stiffnesses {
    /// axial stiffness EA [N]
    pub ea_n: f64,
    /// shear stiffnesses GA1, GA2 along d1, d2 [N], shear correction included
    pub ga_n: [f64; 2],
    /// bending stiffnesses EI1, EI2 about d1, d2 [N m²]
    pub ei_nm2: [f64; 2],
    /// torsional stiffness GJ [N m²]
    pub gj_nm2: f64,
    /// mass per length ρA [kg/m], if given
    pub rho_a_kg_per_m: Option<f64>,
    /// rotary inertias ρI1, ρI2, ρJ [kg m], if given
    pub rho_i_kg_m: Option<[f64; 3]>,
}

impl Stiffnesses {
    /// The radius of gyration `√(min(EI1, EI2)/EA)` [m] of the slenderness check.
    pub fn radius_of_gyration_m(&self) -> f64 {
        (self.ei_nm2[0].min(self.ei_nm2[1]) / self.ea_n).sqrt()
    }
}

/// The constant coefficient diagonals of the rod model on the reference configuration (j = 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RodProperties {
    /// `K0 = diag(kGA, kGA, EA)` [N], eqs. (12), (37).
    pub shear_stretch_n: Vector3<f64>,
    /// `J0 = diag(E I1, E I2, G I3)` [N m²], eqs. (16), (39).
    pub bend_twist_nm2: Vector3<f64>,
    /// `I0 = ρ diag(I1, I2, I3)` [kg m], eqs. (8), (38).
    pub rotary_inertia_kg_m: Vector3<f64>,
    /// Mass per unit length `ρ A0` [kg/m].
    pub mass_per_length_kg_m: f64,
}

impl RodProperties {
    /// The diagonals of a section given by its stiffnesses (D24): `K0 = diag(GA1, GA2, EA)`,
    /// `J0 = diag(EI1, EI2, GJ)`, `I0 = diag(ρI1, ρI2, ρJ)`; a missing ρA is 1 kg/m and missing
    /// inertias 1 kg m (a static analysis never uses them; dynamics and modes require them).
    pub fn from_stiffnesses(s: &Stiffnesses) -> Self {
        RodProperties {
            shear_stretch_n: Vector3::new(s.ga_n[0], s.ga_n[1], s.ea_n),
            bend_twist_nm2: Vector3::new(s.ei_nm2[0], s.ei_nm2[1], s.gj_nm2),
            rotary_inertia_kg_m: Vector3::from(s.rho_i_kg_m.unwrap_or([1.0; 3])),
            mass_per_length_kg_m: s.rho_a_kg_per_m.unwrap_or(1.0),
        }
    }

    /// Explicit conversion from material and cross-section (no faked parameters).
    pub fn new(material: &Material, section: &CrossSection) -> Self {
        let area = section.area_m2();
        let m = section.second_moments_m4();
        let (e, g, rho) = (material.young_modulus_pa, material.shear_modulus_pa, material.density_kg_m3);
        let kga = material.shear_correction * g * area;
        RodProperties {
            shear_stretch_n: Vector3::new(kga, kga, e * area),
            bend_twist_nm2: Vector3::new(e * m[0], e * m[1], g * m[2]),
            rotary_inertia_kg_m: m * rho,
            mass_per_length_kg_m: rho * area,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_matches_remark_2() {
        let r = 1e-3 / 40.0;
        let mat = Material {
            young_modulus_pa: 1.1e5,
            shear_modulus_pa: 5e4,
            density_kg_m3: 1e3,
            shear_correction: 4.0 / 3.0,
        };
        let p = RodProperties::new(&mat, &CrossSection::Circle { radius_m: r });
        let a = std::f64::consts::PI * r * r;
        let pi = std::f64::consts::PI;
        assert!((p.bend_twist_nm2[0] / (1.1e5 * a * a / (4.0 * pi)) - 1.0).abs() < 1e-15);
        assert!((p.bend_twist_nm2[2] / (5e4 * a * a / (2.0 * pi)) - 1.0).abs() < 1e-15);
        assert!((p.rotary_inertia_kg_m[2] / (1e3 * a * a / (2.0 * pi)) - 1.0).abs() < 1e-15);
        // Also equals E π r⁴/4 for the circle.
        assert!((p.bend_twist_nm2[0] / (1.1e5 * pi * r.powi(4) / 4.0) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn rectangle_matches_section_5_1() {
        let mat = Material {
            young_modulus_pa: 7.1e10,
            shear_modulus_pa: 2.69e10,
            density_kg_m3: 2.73e3,
            shear_correction: 0.833,
        };
        let p = RodProperties::new(&mat, &CrossSection::Rectangle { width_m: 0.06, height_m: 0.04 });
        let (a, b) = (0.06_f64, 0.04_f64);
        assert!((p.bend_twist_nm2[0] / (7.1e10 * a * b.powi(3) / 12.0) - 1.0).abs() < 1e-14);
        assert!((p.bend_twist_nm2[1] / (7.1e10 * a.powi(3) * b / 12.0) - 1.0).abs() < 1e-14);
        assert!((p.bend_twist_nm2[2] / (2.69e10 * (a * b.powi(3) + a.powi(3) * b) / 12.0) - 1.0).abs() < 1e-14);
        assert!((p.rotary_inertia_kg_m[2] - p.rotary_inertia_kg_m[0] - p.rotary_inertia_kg_m[1]).abs() < 1e-18);
        assert!((p.shear_stretch_n[0] - 0.833 * 2.69e10 * a * b).abs() < 1e-3);
    }
}
