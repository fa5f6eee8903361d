//! Exact shadows: [`raster`] turns posed shapes into the shadow a point light casts on
//! the receiver, as a bit-packed [`mask::Mask`] whose counts the energies use.

pub mod mask;
pub mod raster;
