//! The analysis of recorded data, below the solvers that use it (`docs/architecture.md`): a
//! frame's noise level from its own positions and a recording's from its frames' (`noise`,
//! `docs/noise.md` N2, N12), how well a reconstruction follows its data and the gate that flags
//! the frames that do not (`fit`, `docs/certificate.md` C5), and the generic baseline, a GCV
//! smoothing spline of each frame (`smoothing`, `docs/noise.md` N4). Nothing here solves a rod:
//! the engines (the automatic weights, the chart and start of a noisy frame), the clips (the body
//! length of a noisy recording) and the noise study use it alike.
pub mod fit;
pub mod noise;
pub mod smoothing;
