//! # cosserat — forward and inverse special Cosserat rods after Wang et al. (2023)
//!
//! A Rust implementation of the monolithic optimal-control method for Cosserat rods of
//! [R1], cross-validated against an independent FreeFEM implementation (`freefem/`).
//! This release contains the forward problem: the static primal equation (52) and the
//! dynamic weak form (40) with the time scheme of Appendix A.
//!
//! ## Model
//! Unknowns along the reference arc length `s ∈ [0, L]`: centreline `x(s, t)` and the angles
//! `α = (α, β, γ)` of the frame `Q = Rz(α) Rx(β) Ry(γ)` (eq. 1). Balance laws (5), (6) with the
//! constitutive laws (11), (15), in weak form (40) with `j = 1`. All decisions where the paper
//! is ambiguous are in `docs/decisions.md` (D1–D8).
//!
//! ## Notation
//! | symbol | Rust name | unit |
//! |---|---|---|
//! | `x = (x, y, z)` | `Dof::X..Dof::Z` | m |
//! | `α = (α, β, γ)` | `Dof::Alpha..Dof::Gamma` | rad |
//! | `Q`, `A`, `d3` | [`rotation::rotation`], [`rotation::a_matrix`], [`rotation::d3`] | – |
//! | `K0 = diag(kGA, kGA, EA)` | `RodProperties::shear_stretch_n` | N |
//! | `J0 = diag(EI1, EI2, GI3)` | `RodProperties::bend_twist_nm2` | N m² |
//! | `I0 = ρ diag(I1, I2, I3)` | `RodProperties::rotary_inertia_kg_m` | kg m |
//! | `ρA0` | `RodProperties::mass_per_length_kg_m` | kg/m |
//! | `n`, `m` | internal force / moment (global components) | N, N m |
//! | `f`, `l` | distributed force / torque | N/m, N m/m |
//! | `w` | `relaxation` (Remark 10) | – |
//!
//! ## References
//! 1. [R1] Y. Wang, T. Ranner, T. P. Ilett, Y. Xia, N. Cohen, *A monolithic optimal control
//!    method for displacement tracking of Cosserat rod with application to reconstruction of
//!    C. elegans locomotion*, Computational Mechanics 71 (2023).
//! 2. [R2] D. Q. Cao, R. W. Tucker, *Nonlinear dynamics of elastic rods using the Cosserat
//!    theory*, Int. J. Solids Struct. 45 (2008) — the §5.1 benchmark.
//! 3. [R3] K. E. Bisshopp, D. C. Drucker, *Large deflection of cantilever beams*, Q. Appl. Math.
//!    3 (1945) — elastica reference values.
pub mod assembly;
pub mod banded;
pub mod case;
pub mod chart;
pub mod clip;
pub mod data;
pub mod element;
pub mod expr;
pub mod freefem;
pub mod loads;
pub mod material;
pub mod mesh;
pub mod metrics;
pub mod output;
pub mod plot;
pub mod reference;
pub mod rotation;
pub mod run;
pub mod solve;
pub mod sweep;
pub mod theory;
pub mod vtk;
