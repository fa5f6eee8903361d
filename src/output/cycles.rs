//! The comparison behind `bsa validate`: Blender Cycles' render of the shadow at `t`
//! against the project's rasterizer.
//!
//! [`cycles_mask`] turns the mask image that `blender/render_shadow.py` renders into a
//! [`Mask`] of the target's size, [`compare`] measures it against the rasterizer's shadow
//! of the same launch (IoU, XOR pixel count, shadow pixel counts, and the four-colour
//! difference image), and [`Comparison::report`] is the content of `validate.json`.
//! Nothing here touches the filesystem: the caller reads the render and writes the
//! results.

use std::path::Path;

use image::{GrayImage, RgbImage};

use crate::energy::{self, Weights};
use crate::evaluate::Problem;
use crate::output::picture;
use crate::shadow::mask::Mask;

/// Grey levels below this are shadow in the Cycles render: the script renders shadow as
/// black on white, and the midpoint splits the anti-aliased edge pixels evenly.
const SHADOW_BELOW: u8 = 128;

/// Why the Cycles render cannot be compared.
#[derive(Debug, thiserror::Error)]
pub enum CyclesError {
    /// The render does not have the target's size, so its pixels are not the target's.
    #[error("the Cycles mask is {width}x{height}, the target {target_width}x{target_height}")]
    Size {
        width: u32,
        height: u32,
        target_width: usize,
        target_height: usize,
    },
}

/// The Cycles render `img` as a mask of `target`'s size: dark pixels are shadow.
pub fn cycles_mask(img: &GrayImage, target: &Mask) -> Result<Mask, CyclesError> {
    if (img.width() as usize, img.height() as usize) != (target.width(), target.height()) {
        return Err(CyclesError::Size {
            width: img.width(),
            height: img.height(),
            target_width: target.width(),
            target_height: target.height(),
        });
    }
    Ok(Mask::from_fn(target.width(), target.height(), |x, y| {
        img.get_pixel(x as u32, y as u32).0[0] < SHADOW_BELOW
    }))
}

/// Cycles' shadow against the rasterizer's.
pub struct Comparison {
    /// Intersection over union of the two shadows.
    pub iou: f64,
    /// Pixels in exactly one of the two shadows.
    pub xor_pixels: u64,
    pub cycles_shadow_pixels: u64,
    pub rasterizer_shadow_pixels: u64,
    /// Black where both shadows are, red where only Cycles', blue where only the
    /// rasterizer's ([`picture::difference_image`]).
    pub difference: RgbImage,
}

/// Compare the Cycles shadow `cycles` with the rasterizer's shadow at `t` of the launch
/// values `params`.
pub fn compare(problem: &Problem, params: &[f64], cycles: &Mask) -> Comparison {
    compare_at(problem, params, problem.scene.t, cycles)
}

/// [`compare`] at the instant `time` (a picture's instant of a scene with several).
pub fn compare_at(problem: &Problem, params: &[f64], time: f64, cycles: &Mask) -> Comparison {
    let mut ws = problem.workspace();
    problem.evaluate(params, &Weights::all_ones(), &mut ws);
    if time != problem.scene.t {
        problem.shadow_at(time, &mut ws);
    }
    // Cycles renders the picture only; the solver's canvas reaches beyond it.
    let ours = &problem.picture_of(&ws.mask);
    let difference = picture::difference_image(
        cycles.width(),
        cycles.height(),
        &|x, y| cycles.get(x, y),
        &|x, y| ours.get(x, y),
    );
    Comparison {
        iou: energy::iou(cycles, ours),
        xor_pixels: cycles.xor_count(ours),
        cycles_shadow_pixels: cycles.count(),
        rasterizer_shadow_pixels: ours.count(),
        difference,
    }
}

impl Comparison {
    /// The content of `validate.json`: the figures, where the mask and the difference
    /// image were saved, and what the Blender script reported.
    pub fn report(
        &self,
        scene: &str,
        cycles_mask: &Path,
        difference_image: &Path,
        blender: serde_json::Value,
    ) -> serde_json::Value {
        serde_json::json!({
            "scene": scene,
            "iou": self.iou,
            "xor_pixels": self.xor_pixels,
            "cycles_shadow_pixels": self.cycles_shadow_pixels,
            "rasterizer_shadow_pixels": self.rasterizer_shadow_pixels,
            "cycles_mask": cycles_mask.display().to_string(),
            "difference_image": difference_image.display().to_string(),
            "blender": blender,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dark_pixels_are_shadow_and_the_size_must_match() {
        let target = Mask::from_fn(3, 2, |_, _| false);
        let img = GrayImage::from_fn(3, 2, |x, _| image::Luma([if x == 1 { 127 } else { 128 }]));
        let mask = cycles_mask(&img, &target).unwrap();
        assert_eq!(mask.count(), 2);
        assert!(mask.get(1, 0) && mask.get(1, 1) && !mask.get(0, 0) && !mask.get(2, 1));
        let small = GrayImage::new(2, 2);
        let err = cycles_mask(&small, &target).unwrap_err();
        assert_eq!(err.to_string(), "the Cycles mask is 2x2, the target 3x2");
    }
}
