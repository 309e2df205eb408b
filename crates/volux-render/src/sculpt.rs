//! Sculpting a grid (seed `004_...txt` ch. 4-6) on top of the engine: the sculpt mask as part
//! of field sampling (`masked.rs`, used by every path of the grid ray caster), picking the
//! visible surface ([`mod@pick`]), label colouring ([`labels`]) and the sculpt state with
//! undo, redo and saved steps ([`state`]). The mask and the tools' regions are in [`volux_core::sculpt`].

pub mod labels;
pub(crate) mod masked;
pub mod pick;
pub mod state;
#[cfg(test)]
mod tests;

pub use labels::LabelVolume;
pub use pick::{pick, SurfacePoint, DEFAULT_PICK_OPACITY};
pub use state::{pixel_size_at, polyline_length, Sculpt, SculptStep};
