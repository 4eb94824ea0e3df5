//! `[clip]`: a recorded, kymogram or synthetic clip, on a mesh fine enough for the clip's
//! measures.
use std::path::Path;

use nalgebra::{Rotation3, Vector3};

use super::super::raw::{RawClip, RawClipKind, RawMissing, RawPlane, RawRotation, RawStart};
use super::super::{CaseError, ClipKind, ClipPlacement, ClipSource, RecordingKeys, Section, SyntheticClip};
use super::Validator;
use crate::clip::missing::MissingData;
use crate::clip::recording::{LengthUnit, UnitSpec};
use crate::clip::synthetic::RollClipParams;
use crate::clip::{ClipPlane, CLIP_SKIP_ELEMENTS, MAX_CLIP_POSITIONS, MIN_CLIP_ELEMENTS};
use crate::model::mesh::Mesh;
use crate::recorded::fit::FitGate;
use crate::solve::sequence::{FrameStart, RotationTreatment};

impl Validator<'_> {
    /// `[clip]`: a recorded or synthetic clip. The stages, in the order their errors are
    /// reported: the mesh, the frame range and chart guard, the placement, the kind (with the
    /// `roll_3d` keys), the treatment of untracked nodes, the fit-quality gate.
    pub(super) fn clip(&self, cl: &RawClip, mesh: &Mesh, section: &Section) -> Result<ClipSource, CaseError> {
        self.clip_mesh(cl, mesh)?;
        let base = self.path.parent().unwrap_or(Path::new(""));
        let frames = self.clip_frames(cl)?;
        if !(cl.min_cos_beta >= 0.0 && cl.min_cos_beta < 1.0) {
            return Err(self.err("clip.min_cos_beta", format!("must lie in [0, 1), got {}", cl.min_cos_beta)));
        }
        let placement = self.clip_placement(cl)?;
        let kind = self.clip_kind(cl, mesh)?;
        let missing = self.clip_missing(cl, &kind)?;
        let gate = self.clip_gate(cl, section)?;
        let recording = self.clip_recording(cl, &kind, &placement)?;
        Ok(ClipSource {
            kind,
            file: base.join(&cl.file),
            gate,
            missing,
            frames,
            min_cos_beta: cl.min_cos_beta,
            start: match cl.start {
                RawStart::PreviousFrame => FrameStart::PreviousFrame,
                RawStart::DataGuess => FrameStart::DataGuess,
            },
            rotation: match cl.rotation {
                RawRotation::Rebased => RotationTreatment::Rebased,
                RawRotation::GlobalEuler => RotationTreatment::GlobalEuler,
            },
            placement,
            recording,
        })
    }

    /// The keys of a recording's file: `clip.unit` with `clip.scale_m_per_px`, `clip.worm_id`
    /// (WCON) and `clip.data_plane` (rotated by `clip.orientation`, as the data are).
    fn clip_recording(
        &self,
        cl: &RawClip,
        kind: &ClipKind,
        placement: &ClipPlacement,
    ) -> Result<RecordingKeys, CaseError> {
        let given = cl.unit.is_some() || cl.scale_m_per_px.is_some() || cl.worm_id.is_some() || cl.data_plane.is_some();
        if given && *kind != ClipKind::Recording {
            return Err(
                self.err("clip", "unit, scale_m_per_px, worm_id and data_plane apply to kind = \"recording\" only")
            );
        }
        let unit = match &cl.unit {
            None => None,
            Some(u) => Some(LengthUnit::parse(u.trim()).ok_or_else(|| {
                self.err("clip.unit", format!("\"{u}\" is not a unit of length: \"m\", \"mm\", \"um\" or \"px\""))
            })?),
        };
        let m_per_px = cl.scale_m_per_px.as_ref().map(|v| self.positive("clip.scale_m_per_px", v)).transpose()?;
        if m_per_px.is_some() && unit.is_some_and(|u| u != LengthUnit::Pixel) {
            return Err(self.err("clip.scale_m_per_px", "applies to positions in pixels (clip.unit = \"px\") only"));
        }
        let data_plane = match cl.data_plane {
            None => None,
            Some(n) => {
                let v = Vector3::from(n);
                let norm = v.norm();
                if !(norm.is_finite() && norm > 1e-12) {
                    return Err(self.err("clip.data_plane", format!("must be a finite non-zero vector, got {n:?}")));
                }
                Some(placement.orientation * (v / norm))
            }
        };
        Ok(RecordingKeys { units: UnitSpec { unit, m_per_px }, worm_id: cl.worm_id.clone(), data_plane })
    }

    /// A clip case's mesh has at least [`MIN_CLIP_ELEMENTS`] elements.
    fn clip_mesh(&self, cl: &RawClip, mesh: &Mesh) -> Result<(), CaseError> {
        if mesh.elements >= MIN_CLIP_ELEMENTS {
            return Ok(());
        }
        Err(self.err(
            "rod.elements",
            format!(
                "a clip case needs at least {MIN_CLIP_ELEMENTS} elements ({} nodes per frame of clip.file `{}`), \
                 got {} ({} nodes): the clip's measures leave out {CLIP_SKIP_ELEMENTS} elements at each end \
                 (curvature errors, ground truth) and the roughness needs 3 curvature values",
                MIN_CLIP_ELEMENTS + 1,
                cl.file.display(),
                mesh.elements,
                mesh.nodes()
            ),
        ))
    }

    /// `clip.frames`: the `[first, end)` frame range, all frames if absent.
    fn clip_frames(&self, cl: &RawClip) -> Result<Option<(usize, usize)>, CaseError> {
        match cl.frames {
            Some([a, b]) if a < b => Ok(Some((a, b))),
            Some([a, b]) => {
                Err(self.err("clip.frames", format!("expected [first, end) with first < end, got [{a}, {b}]")))
            }
            None => Ok(None),
        }
    }

    /// `clip.plane`, `clip.orientation` (a rotation vector [rad]) and `clip.gauge` (R7): where
    /// the frames are placed in space and the gauge vector rotated with them.
    fn clip_placement(&self, cl: &RawClip) -> Result<ClipPlacement, CaseError> {
        let plane = match cl.plane {
            RawPlane::Xz => ClipPlane::Xz,
            RawPlane::Xy => ClipPlane::Xy,
        };
        if let Some(v) = cl.orientation.iter().flatten().find(|v| !v.is_finite()) {
            return Err(self.err("clip.orientation", format!("must be a finite rotation vector [rad], got {v}")));
        }
        let orientation = Rotation3::new(Vector3::from(cl.orientation.unwrap_or([0.0; 3]))).into_inner();
        if orientation.iter().any(|c| !c.is_finite()) {
            return Err(self.err(
                "clip.orientation",
                format!("rotation vector {:?} [rad] is too long: its angle is not finite", cl.orientation),
            ));
        }
        let gauge = match cl.gauge {
            Some(g) => {
                let v = Vector3::from(g);
                let norm = v.norm();
                if !(norm.is_finite() && norm > 1e-12) {
                    return Err(self.err("clip.gauge", format!("must be a finite non-zero vector, got {g:?}")));
                }
                v / norm
            }
            None => match plane {
                ClipPlane::Xz => Vector3::y(),
                ClipPlane::Xy => Vector3::z(),
            },
        };
        Ok(ClipPlacement { plane, orientation, gauge: orientation * gauge })
    }

    /// `clip.kind` with `clip.frame_interval_s` [s]; the `roll_3d` keys belong to that kind
    /// only.
    fn clip_kind(&self, cl: &RawClip, mesh: &Mesh) -> Result<ClipKind, CaseError> {
        let frame_interval_s = self.positive("clip.frame_interval_s", &cl.frame_interval_s)?;
        let kind = match cl.kind {
            RawClipKind::Kymogram => ClipKind::Kymogram,
            RawClipKind::Recording => ClipKind::Recording,
            RawClipKind::Roll3d => ClipKind::Roll3d(self.synthetic(cl, mesh, frame_interval_s)?),
        };
        let roll_keys = cl.roll_total_rad.is_some()
            || cl.twist_per_m.is_some()
            || cl.clip_frames.is_some()
            || cl.substeps.is_some();
        if !matches!(kind, ClipKind::Roll3d(_)) && roll_keys {
            return Err(self.err(
                "clip",
                "roll_total_rad, twist_per_m, clip_frames and substeps apply to kind = \"roll_3d\" only",
            ));
        }
        Ok(kind)
    }

    /// `clip.missing`: what marks an untracked node (recordings only).
    fn clip_missing(&self, cl: &RawClip, kind: &ClipKind) -> Result<MissingData, CaseError> {
        match (cl.missing, kind) {
            (None, _) => Ok(MissingData::Error),
            (Some(RawMissing::Nan), ClipKind::Recording) => Ok(MissingData::Nan),
            (Some(_), _) => Err(self.err(
                "clip.missing",
                "applies to kind = \"recording\" only (kymograms and synthetic clips have no untracked nodes)",
            )),
        }
    }

    /// `clip.gate_*`, `clip.noise_m` and `clip.max_curvature_per_m`: the fit-quality gate, each
    /// bound positive, the default where absent (the curvature's: the inverse of the
    /// cross-section's smallest half-width, [`FitGate::curvature_bound`]).
    fn clip_gate(&self, cl: &RawClip, section: &Section) -> Result<FitGate, CaseError> {
        let d = FitGate::default();
        let gate_key = |key: &str, v: Option<f64>, default: f64| match v {
            None => Ok(default),
            Some(v) if v > 0.0 && v.is_finite() => Ok(v),
            Some(v) => Err(self.err(key, format!("must be a positive number, got {v}"))),
        };
        Ok(FitGate {
            noise_multiple: gate_key("clip.gate_noise_multiple", cl.gate_noise_multiple, d.noise_multiple)?,
            position_min: gate_key("clip.gate_position", cl.gate_position, d.position_min)?,
            tangent_min: gate_key("clip.gate_tangent", cl.gate_tangent, d.tangent_min)?,
            noise_m: cl.noise_m.as_ref().map(|v| self.positive("clip.noise_m", v)).transpose()?,
            max_curvature_per_m: match &cl.max_curvature_per_m {
                Some(v) => self.positive("clip.max_curvature_per_m", v)?,
                // a section given by its stiffnesses has no width: no bound unless stated
                None => match section {
                    Section::Shape(cs) => FitGate::curvature_bound(cs),
                    Section::Stiffness(_) => f64::INFINITY,
                },
            },
        })
    }

    /// The `roll_3d` keys of `[clip]` (nodes, length and Δt are the mesh's and the clip's).
    fn synthetic(&self, cl: &RawClip, mesh: &Mesh, dt_s: f64) -> Result<SyntheticClip, CaseError> {
        let d = RollClipParams::default();
        let synthetic = SyntheticClip {
            frames: cl.clip_frames.unwrap_or(d.frames),
            roll_total_rad: cl
                .roll_total_rad
                .as_ref()
                .map(|v| self.scalar("clip.roll_total_rad", v))
                .transpose()?
                .unwrap_or(d.roll_total_rad),
            twist_per_m: cl
                .twist_per_m
                .as_ref()
                .map(|v| self.scalar("clip.twist_per_m", v))
                .transpose()?
                .unwrap_or(d.twist_per_m),
            time_mapping: d.time_mapping,
            substeps: cl.substeps.unwrap_or(d.substeps),
        };
        synthetic.params(mesh, dt_s).validate().map_err(|e| self.err("clip", e.to_string()))?;
        let positions = synthetic.frames.saturating_mul(mesh.nodes());
        if positions > MAX_CLIP_POSITIONS {
            return Err(self.err(
                "clip.clip_frames",
                format!(
                    "{} frames × {} nodes are {positions} positions: too many, the limit of a clip is {MAX_CLIP_POSITIONS}",
                    synthetic.frames,
                    mesh.nodes()
                ),
            ));
        }
        Ok(synthetic)
    }
}
