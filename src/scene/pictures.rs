//! Validation of the scene's pictures and of how long they hold: the single form
//! (`target` and `t`) or the sequence (`targets`), the `hold` window and the launch
//! `positions`. Every error names the file and the field.

use std::path::PathBuf;

use super::raw::{RawHints, RawHold, RawScene};
use super::validate::Validator;
use super::*;

/// A picture before its hints are read (they need the occluders).
pub(super) struct PictureSpec<'a> {
    pub(super) target: Mask,
    pub(super) file: PathBuf,
    pub(super) t: f64,
    pub(super) weight: f64,
    /// The hints and the field they come from.
    pub(super) hints: Option<(&'a RawHints, String)>,
}

impl Validator<'_> {
    /// The pictures of the scene in order of their instants, with weights that sum to 1:
    /// `target` and `t`, or `targets`; never both.
    pub(super) fn pictures<'r>(&self, raw: &'r RawScene) -> Result<Vec<PictureSpec<'r>>> {
        let Some(list) = &raw.targets else {
            let rel = raw.target.as_ref().ok_or_else(|| {
                self.field_err(
                    "target",
                    "is required (or give `targets`: a list of {target, t, weight})",
                )
            })?;
            let t = raw.t.ok_or_else(|| {
                self.field_err(
                    "t",
                    "is required (or give `targets`: a list of {target, t, weight})",
                )
            })?;
            let t = self.instant("t", t)?;
            return Ok(vec![PictureSpec {
                target: self.target("target", rel)?,
                file: self.resolve(rel),
                t,
                weight: 1.0,
                hints: raw.hints.as_ref().map(|h| (h, "hints".to_string())),
            }]);
        };
        for (field, given) in [
            ("target", raw.target.is_some()),
            ("t", raw.t.is_some()),
            ("hints", raw.hints.is_some()),
        ] {
            if given {
                return Err(self.field_err(
                    field,
                    "cannot be given with `targets`: each entry of `targets` holds its own target, t and hints",
                ));
            }
        }
        if list.is_empty() || list.len() > MAX_PICTURES {
            return Err(self.field_err(
                "targets",
                format!("needs 1 to {MAX_PICTURES} entries, got {}", list.len()),
            ));
        }
        let mut out: Vec<PictureSpec> = Vec::with_capacity(list.len());
        for (k, p) in list.iter().enumerate() {
            let f = |s: &str| format!("targets[{k}].{s}");
            let rel = p.target.as_ref().ok_or_else(|| {
                self.field_err(f("target"), "is required: the picture's PNG file")
            })?;
            let t = p.t.ok_or_else(|| {
                self.field_err(f("t"), "is required: the instant of the picture (s)")
            })?;
            let t = self.instant(&f("t"), t)?;
            if let Some(prev) = out.last() {
                if t <= prev.t {
                    return Err(self.field_err(
                        f("t"),
                        format!(
                            "must be later than the previous picture's t = {} s, got {t} s: give the pictures in the order of their instants",
                            prev.t
                        ),
                    ));
                }
            }
            let weight = self.weight(&f("weight"), p.weight.unwrap_or(1.0))?;
            if weight == 0.0 {
                return Err(self.field_err(f("weight"), "must be positive"));
            }
            let target = self.target(&f("target"), rel)?;
            if let Some(first) = out.first() {
                let (w, h) = (first.target.width(), first.target.height());
                if (target.width(), target.height()) != (w, h) {
                    return Err(self.field_err(
                        f("target"),
                        format!(
                            "is {} x {} pixels, the first picture {w} x {h}: every picture of a scene has the same size",
                            target.width(),
                            target.height()
                        ),
                    ));
                }
            }
            out.push(PictureSpec {
                target,
                file: self.resolve(rel),
                t,
                weight,
                hints: p.hints.as_ref().map(|h| (h, f("hints"))),
            });
        }
        let sum: f64 = out.iter().map(|p| p.weight).sum();
        for p in &mut out {
            p.weight /= sum;
        }
        Ok(out)
    }

    /// The pictures with their hints read (they name occluders).
    pub(super) fn with_hints(
        &self,
        specs: Vec<PictureSpec>,
        occluders: &[Occluder],
    ) -> Result<Vec<Picture>> {
        let mut pictures = Vec::with_capacity(specs.len());
        for spec in specs {
            let hints = match spec.hints {
                None => Vec::new(),
                Some((RawHints::Inline(list), field)) => list
                    .iter()
                    .enumerate()
                    .map(|(i, h)| self.hint(&format!("{field}[{i}]"), h, occluders))
                    .collect::<Result<_>>()?,
                Some((RawHints::File(rel), field)) => {
                    self.hints_file(&field, &self.resolve(rel), occluders)?
                }
            };
            pictures.push(Picture {
                target: spec.target,
                file: spec.file,
                t: spec.t,
                weight: spec.weight,
                hints,
            });
        }
        Ok(pictures)
    }

    /// A hold objective: `"mean"` or `"worst"`.
    pub(super) fn objective(
        &self,
        field: &str,
        raw: Option<&str>,
    ) -> Result<Option<HoldObjective>> {
        match raw {
            None => Ok(None),
            Some("mean") => Ok(Some(HoldObjective::Mean)),
            Some("worst") => Ok(Some(HoldObjective::Worst)),
            Some(other) => Err(self.field_err(
                field,
                format!("must be \"mean\" or \"worst\", got \"{other}\""),
            )),
        }
    }

    /// The hold window: positive, starting after the launch, with at least two instants
    /// to evaluate.
    pub(super) fn hold(&self, raw: &RawHold, first_t: f64, dt: f64) -> Result<Hold> {
        let window = self.positive_within("hold.window", raw.window, MAX_T)?;
        if window >= first_t {
            return Err(self.field_err(
                "hold.window",
                format!(
                    "{window} s reaches back to the launch (the first picture is at {first_t} s): the window must start after it"
                ),
            ));
        }
        let fps = match raw.fps {
            Some(fps) => self.positive_within("hold.fps", fps, 1e6)?,
            None => 1.0 / dt,
        };
        let objective = self
            .objective("hold.objective", raw.objective.as_deref())?
            .unwrap_or(HoldObjective::Mean);
        let hold = Hold {
            window,
            instants: raw.instants,
            fps,
            objective,
        };
        match raw.instants {
            Some(0) => {
                return Err(self.field_err(
                    "hold.instants",
                    "is 0: the window needs at least 2 instants to evaluate",
                ))
            }
            Some(1) => {
                return Err(self.field_err(
                    "hold.instants",
                    "is 1: one instant is the picture's own; give at least 2 (the window's ends), or remove `hold`",
                ))
            }
            Some(n) if n > MAX_INSTANTS => {
                return Err(self.field_err(
                    "hold.instants",
                    format!("must be at most {MAX_INSTANTS}, got {n}"),
                ))
            }
            _ => {}
        }
        let frames = hold.frame_offsets().len();
        if raw.instants.is_none() && frames < 2 {
            return Err(self.field_err(
                "hold.window",
                format!(
                    "of {window} s holds no frame but the picture's own at {fps} frames per second: widen it, or give `hold.fps` or `hold.instants`"
                ),
            ));
        }
        if frames > MAX_INSTANTS {
            return Err(self.field_err(
                "hold.fps",
                format!(
                    "gives {frames} frames in the window, more than the {MAX_INSTANTS} allowed"
                ),
            ));
        }
        Ok(hold)
    }

    /// `"fixed"` (default) or `"free"`; free positions need a table to be bounded to.
    pub(super) fn positions(&self, raw: Option<&str>, has_table: bool) -> Result<LaunchPositions> {
        match raw {
            None | Some("fixed") => Ok(LaunchPositions::Fixed),
            Some("free") if has_table => Ok(LaunchPositions::Free),
            Some("free") => Err(self.field_err(
                "positions",
                "\"free\" launch positions are bounded to the table's top: the scene needs a `table`",
            )),
            Some(other) => Err(self.field_err(
                "positions",
                format!("must be \"fixed\" or \"free\", got \"{other}\""),
            )),
        }
    }
}
