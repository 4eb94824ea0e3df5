//! The files a case runs on, read alike by both engines: the data file of an inverse case
//! (`data.csv`, I7: [`data`]), the recordings of a clip ([`clip_files`]) with the ground truth
//! beside them ([`truth_file`]), and the corpus of synthetic recordings `cosserat synth` writes
//! ([`corpus`]).
pub mod clip_files;
pub mod corpus;
pub mod data;
pub mod truth_file;
