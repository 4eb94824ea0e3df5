//! The files a case runs on, read alike by both engines: the data file of an inverse case
//! (`data.csv`, I7: [`data`]), the recordings of a clip ([`clip_files`]) with the ground truth
//! beside them ([`truth_file`]) read by [`recording`] (CSV, NPY, WCON), and the corpora of
//! synthetic recordings `cosserat synth` writes ([`corpus`]: 3D; [`tracker`]: as a
//! single-camera tracker writes them).
pub mod clip_files;
pub mod corpus;
pub mod data;
pub mod recording;
pub mod recording_stream;
pub mod resolve;
pub mod tracker;
pub mod truth_file;
