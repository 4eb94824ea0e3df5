//! Readers and writers of file formats, knowing nothing of rods or runs: atomic writes, capped
//! reads and CSV ([`files`], with the errors of every reader and writer), NumPy `.npy` arrays
//! ([`npy`]), numbers as text ([`number`]), ParaView VTK files ([`vtk`]), the compact clip
//! fields `fields.npz` ([`compact`], written in bounded memory by [`compact_write`]) and a full disk recognised in an error ([`disk`]).
pub mod compact;
pub mod compact_write;
pub mod disk;
pub mod files;
pub mod npy;
pub mod number;
pub mod vtk;

pub use files::{write_atomic, InputError, OutputError};
