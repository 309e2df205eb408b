//! Text drawn over pictures (the 3D view, the slices): on a dark, semi-opaque rounded
//! backing, so that it reads over any data (yellow over beige skin, grey over bone) and over
//! the lines drawn under it.
use eframe::egui::{self, Align2, Color32, FontId, Pos2, Rect};

/// The backing's colour: black, two thirds opaque.
pub const BACKING: Color32 = Color32::from_black_alpha(170);

/// Margin of the backing around the text (points).
const MARGIN: egui::Vec2 = egui::vec2(3.0, 1.0);

/// Draws `text` at `pos` (the point `align` names) on a dark backing; returns the
/// backing's rectangle.
pub fn backed_text(
    painter: &egui::Painter,
    pos: Pos2,
    align: Align2,
    text: &str,
    font: FontId,
    colour: Color32,
) -> Rect {
    let galley = painter.layout_no_wrap(text.to_string(), font, colour);
    let text_rect = align.anchor_size(pos, galley.size());
    let backing = text_rect.expand2(MARGIN);
    painter.rect_filled(backing, 3.0, BACKING);
    painter.galley(text_rect.min, galley, colour);
    backing
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The backing is drawn first and covers the text.
    #[test]
    fn the_backing_lies_under_the_whole_text() {
        let ctx = egui::Context::default();
        let mut drawn = Rect::NOTHING;
        let output = ctx.run(egui::RawInput::default(), |ctx| {
            let painter = ctx.layer_painter(egui::LayerId::background());
            drawn = backed_text(
                &painter,
                Pos2::new(100.0, 100.0),
                Align2::LEFT_BOTTOM,
                "12.34 mm",
                FontId::proportional(14.0),
                Color32::YELLOW,
            );
        });
        let shapes: Vec<&egui::Shape> = output.shapes.iter().map(|s| &s.shape).collect();
        let [egui::Shape::Rect(backing), egui::Shape::Text(text)] = shapes.as_slice() else {
            panic!("a rectangle, then the text: {shapes:?}")
        };
        assert_eq!(backing.fill, BACKING);
        assert_eq!(backing.rect, drawn);
        assert!(
            drawn.contains_rect(text.visual_bounding_rect()),
            "{drawn:?}"
        );
        assert_eq!(
            drawn.left_bottom(),
            Pos2::new(100.0, 100.0) + egui::vec2(-3.0, 1.0)
        );
    }
}
