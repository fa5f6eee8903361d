//! Validation of the hints: a hint of the scene file, and the hints text file that a
//! picture may name instead (`occluder x y z px py [weight]` per line).

use std::path::Path;

use glam::DVec2;

use super::Validator;
use crate::scene::raw::RawHint;
use crate::scene::{read_input_text, Hint, Occluder, Result, SceneError, MAX_PIXEL};

impl Validator<'_> {
    /// One hint, `field` naming it in errors: an occluder that exists, a point on it, a
    /// pixel within [`MAX_PIXEL`] and a weight.
    pub(in crate::scene) fn hint(
        &self,
        field: &str,
        h: &RawHint,
        occ: &[Occluder],
    ) -> Result<Hint> {
        let occluder = occ
            .iter()
            .position(|o| o.name == h.occluder)
            .ok_or_else(|| {
                self.field_err(
                    format!("{field}.occluder"),
                    format!("names occluder `{}`, which does not exist", h.occluder),
                )
            })?;
        let point = self.vec3(&format!("{field}.point"), h.point)?;
        let px = self.within(&format!("{field}.pixel[0]"), h.pixel[0], MAX_PIXEL)?;
        let py = self.within(&format!("{field}.pixel[1]"), h.pixel[1], MAX_PIXEL)?;
        let weight = self.weight(&format!("{field}.weight"), h.weight.unwrap_or(1.0))?;
        Ok(Hint {
            occluder,
            point,
            pixel: DVec2::new(px, py),
            weight,
        })
    }

    /// Hints in a text file, one per line: `occluder x y z px py [weight]`; `#` starts a
    /// comment. This is the paper's "hints stored separately in a text file".
    pub(in crate::scene) fn hints_file(
        &self,
        field: &str,
        path: &Path,
        occ: &[Occluder],
    ) -> Result<Vec<Hint>> {
        let text = read_input_text(path).map_err(|error| SceneError::Named {
            path: self.file.to_path_buf(),
            field: field.to_string(),
            named: path.to_path_buf(),
            error,
        })?;
        let mut out = Vec::new();
        for (k, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let err = |reason: String| SceneError::HintLine {
                path: path.to_path_buf(),
                line: k + 1,
                reason,
            };
            let parts: Vec<&str> = line.split_whitespace().collect();
            if parts.len() != 6 && parts.len() != 7 {
                return Err(err(format!(
                    "expected `occluder x y z px py [weight]`, got {} fields",
                    parts.len()
                )));
            }
            let mut nums = [0.0f64; 6];
            for (n, s) in parts[1..].iter().enumerate() {
                let x: f64 = s
                    .parse()
                    .map_err(|_| err(format!("`{s}` is not a number")))?;
                if !x.is_finite() {
                    return Err(err(format!("`{s}` is not a finite number")));
                }
                nums[n] = x;
            }
            let raw = RawHint {
                occluder: parts[0].to_string(),
                point: [nums[0], nums[1], nums[2]],
                pixel: [nums[3], nums[4]],
                weight: if parts.len() == 7 {
                    Some(nums[5])
                } else {
                    None
                },
            };
            let h = self
                .hint(&format!("hints (line {})", k + 1), &raw, occ)
                .map_err(|e| err(e.to_string()))?;
            out.push(h);
        }
        Ok(out)
    }
}
