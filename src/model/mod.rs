//! The rod model: material and cross-section, the rotation kinematics of eqs. (1), (27), (28)
//! and the rebased chart, the mesh with its layout of unknowns and quadrature rules, the loads,
//! and the pure P1 element kernels. Nothing here knows a solver, a case file or a file format.
pub mod balance;
pub mod chart;
pub mod element;
pub mod ends;
pub mod geometry;
pub mod loads;
pub mod material;
pub mod mesh;
pub mod resultants;
pub mod rotation;
