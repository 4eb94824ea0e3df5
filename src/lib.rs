//! # cosserat — forward and inverse special Cosserat rods after Wang et al. (2023)
//!
//! A Rust implementation of the monolithic optimal-control method for Cosserat rods of
//! [R1], cross-validated against an independent FreeFEM implementation (`freefem/`):
//! the forward problem (the static primal equation (52) and the dynamic weak form (40) with
//! the time scheme of Appendix A) and the inverse problem (Problem 2, eq. (61): one frame by
//! the paper's fixed point or by Newton, and whole clips of frames, §6).
//!
//! ## Model
//! Unknowns along the reference arc length `s ∈ [0, L]`: centreline `x(s, t)` and the angles
//! `α = (α, β, γ)` of the frame `Q = Rz(α) Rx(β) Ry(γ)` (eq. 1). Balance laws (5), (6) with the
//! constitutive laws (11), (15), in weak form (40) with `j = 1`. Every reading of an ambiguous
//! or misprinted part of the paper is in `docs/decisions.md` (D1–D14), `docs/inverse.md`
//! (I1–I12) and `docs/rotation.md` (R1–R8).
//!
//! ## Layers
//! Each layer imports only the layers above it in this list (checked by
//! `tests/architecture.rs`):
//! 1. foundation: [`expr`] (load expressions), [`linalg`] (block-tridiagonal systems),
//!    [`reference`] (analytic solutions), [`interrupt`] (the stop requested by a signal),
//!    [`file_kind`] (regular file, pipe, device: an input's kind, found without opening it);
//! 2. [`figures`]: SVG line plots, heatmaps and postures, knowing nothing of rods;
//! 3. [`io`]: readers and writers of file formats (capped reads, CSV, `.npy`, VTK, numbers);
//! 4. [`model`]: material, rotation kinematics and charts, mesh and the layout of the unknowns
//!    ([`model::mesh::DofMap`]), loads, the element kernels;
//! 5. [`assemble`]: the one element loop and the integration of functionals;
//! 6. [`solve`]: statics, dynamics, modes, the inverse problem of a frame, clips of frames;
//! 7. [`clip`]: clips of centrelines (kymogram geometry, the synthetic 3D clip);
//! 8. [`case`]: case files, validated into the solvers' params;
//! 9. [`engine`]: a case in either engine behind one interface: the Rust engine
//!    ([`engine::rust`]: results and metrics), the FreeFEM engine ([`engine::freefem`]) and the
//!    files both read ([`engine::input`]);
//! 10. [`output`]: the output-folder contract (a run's and a clip's files, journal, lock,
//!     manifest);
//! 11. [`jobs`]: a case solved into its folder, sweeps, comparisons of the engines, batches;
//! 12. [`audit`]: the audit of the paper's §5–6 (specs, checks, figures, report), [`study`];
//!     then the `cosserat` binary (CLI).
//!
//! ## Notation
//! | symbol | Rust name | unit |
//! |---|---|---|
//! | `x = (x, y, z)` | [`model::mesh::Field::X`] | m |
//! | `α = (α, β, γ)` | [`model::mesh::Field::Alpha`] | rad |
//! | `x̂`, `α̂` (adjoints) | [`model::mesh::Field::XHat`], [`model::mesh::Field::AlphaHat`] | – |
//! | `Q`, `A`, `d3` | [`model::rotation::rotation`], [`model::rotation::a_matrix`], [`model::rotation::d3`] | – |
//! | `K0 = diag(kGA, kGA, EA)` | `RodProperties::shear_stretch_n` | N |
//! | `J0 = diag(EI1, EI2, GI3)` | `RodProperties::bend_twist_nm2` | N m² |
//! | `I0 = ρ diag(I1, I2, I3)` | `RodProperties::rotary_inertia_kg_m` | kg m |
//! | `ρA0` | `RodProperties::mass_per_length_kg_m` | kg/m |
//! | `n`, `m` | internal force / moment (global components) | N, N m |
//! | `f`, `l` | distributed force / torque | N/m, N m/m |
//! | `λg, λf, λl, λd, Λκ, Λω` | [`solve::inverse::Weights`] | – |
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
pub mod assemble;
pub mod audit;
pub mod case;
pub mod clip;
pub mod engine;
pub mod expr;
pub mod figures;
pub mod file_kind;
pub mod interrupt;
pub mod io;
pub mod jobs;
pub mod linalg;
pub mod model;
pub mod output;
pub mod recorded;
pub mod reference;
pub mod solve;
pub mod study;
