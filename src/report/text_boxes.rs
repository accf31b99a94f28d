//! Where a figure's text lands: a plotters backend that draws nothing but records the box of
//! every text it is given (the same layout, anchor and rotation the real backends use), so that
//! a test can find titles and labels drawn over each other.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters_backend::{
    text_anchor::{HPos, VPos},
    BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind,
};

/// A text and its box in pixels: left, top, right, bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct TextBox {
    pub text: String,
    pub rect: [i32; 4],
}

/// The recording backend (the drawing area owns it; the boxes are shared with the caller).
struct Recorder {
    size: (u32, u32),
    boxes: std::rc::Rc<std::cell::RefCell<Vec<TextBox>>>,
}

impl DrawingBackend for Recorder {
    type ErrorType = std::io::Error;

    fn get_size(&self) -> (u32, u32) {
        self.size
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        Ok(())
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        Ok(())
    }
    fn draw_pixel(
        &mut self,
        _point: BackendCoord,
        _color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        Ok(())
    }
    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        if text.trim().is_empty() || style.color().alpha == 0.0 {
            return Ok(());
        }
        let ((x0, y0), (x1, y1)) = style
            .layout_box(text)
            .map_err(|e| DrawingErrorKind::FontError(Box::new(e)))?;
        let (w, h) = (x1 - x0, y1 - y0);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -w,
            HPos::Center => -w / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -h / 2,
            VPos::Bottom => -h,
        };
        let t = style.transform();
        let (ax, ay) = t.transform(dx, dy);
        let (bx, by) = t.transform(dx + w, dy + h);
        self.boxes.borrow_mut().push(TextBox {
            text: text.to_string(),
            rect: [
                pos.0 + ax.min(bx),
                pos.1 + ay.min(by),
                pos.0 + ax.max(bx),
                pos.1 + ay.max(by),
            ],
        });
        Ok(())
    }
}

/// Every text box of `fig` as drawn at its own size.
pub fn text_boxes(fig: &impl super::Figure) -> anyhow::Result<Vec<TextBox>> {
    super::register_fonts();
    let boxes = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let area: DrawingArea<Recorder, Shift> = Recorder {
        size: fig.size(),
        boxes: boxes.clone(),
    }
    .into_drawing_area();
    fig.draw(&area)?;
    drop(area);
    let out = boxes.borrow().clone();
    Ok(out)
}

/// Pairs of texts of `fig` whose boxes overlap by more than `slack` pixels both ways.
pub fn overlapping_text(
    fig: &impl super::Figure,
    slack: i32,
) -> anyhow::Result<Vec<(TextBox, TextBox)>> {
    let boxes = text_boxes(fig)?;
    let mut out = Vec::new();
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[i + 1..] {
            let ox = a.rect[2].min(b.rect[2]) - a.rect[0].max(b.rect[0]);
            let oy = a.rect[3].min(b.rect[3]) - a.rect[1].max(b.rect[1]);
            if ox > slack && oy > slack {
                out.push((a.clone(), b.clone()));
            }
        }
    }
    Ok(out)
}
