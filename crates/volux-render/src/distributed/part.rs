//! What one rank renders of a distributed frame ([`Part`]) and how the ranks combine their
//! parts into rank 0's image ([`Part::combine`]): partial images composited front to back
//! ([`composite`]), or the split MIP's maxima reduced ([`reduce`] with
//! [`MipPart::merge`]) and coloured on rank 0.
use volux_core::{Image, TransferFunction};

use super::error::DistributedError;
use super::exchange::Exchange;
use super::mip::{MipPart, MIP_CHANNELS};
use super::swap::{composite, reduce, CompositeStats};

/// One rank's part of a distributed frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Part {
    /// The integral of the rays' parts in the region: premultiplied RGBA, no background.
    Over(Image),
    /// The region's MIP maxima, and the transfer function (resolved against the data range)
    /// that colours the reduced maximum.
    Mip(MipPart, TransferFunction),
}

impl Part {
    /// Combines every rank's part (each rank calls it with its own, `order` the view's
    /// visibility order of the ranks, the same on every rank): rank 0 gets the image, the
    /// others `None`.
    pub fn combine<E: Exchange + ?Sized>(
        &self,
        ex: &mut E,
        order: &[usize],
    ) -> Result<(Option<Image>, CompositeStats), DistributedError> {
        match self {
            Part::Over(image) => composite(ex, order, image),
            Part::Mip(part, tf) => {
                let (whole, stats) =
                    reduce(ex, order, part.values.clone(), MIP_CHANNELS, MipPart::merge)?;
                let image = whole
                    .map(|values| {
                        MipPart {
                            width: part.width,
                            height: part.height,
                            values,
                        }
                        .image(tf)
                    })
                    .transpose()?;
                Ok((image, stats))
            }
        }
    }

    /// The partial image ([`Part::Over`]), or the MIP of this part alone, coloured.
    pub fn image(&self) -> Result<Image, DistributedError> {
        match self {
            Part::Over(image) => Ok(image.clone()),
            Part::Mip(part, tf) => part.image(tf),
        }
    }
}
