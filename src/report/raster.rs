//! A bird's-eye RGB frame of the merge section (the Gymnasium environment's `render`): lanes
//! as grey bands with white edges, HDVs light grey, CAVs blue, highlighted vehicles red. The
//! road is drawn in its own frame, stretched across (a 14 m wide road over a 470 m section would
//! be a line otherwise).

use crate::model::scene::{Kind, Scene};

const GRASS: [u8; 3] = [96, 128, 84];
const ASPHALT: [u8; 3] = [72, 72, 76];
const MARKING: [u8; 3] = [235, 235, 235];
const HDV: [u8; 3] = [205, 205, 205];
const CAV: [u8; 3] = [40, 110, 230];
const HIGHLIGHT: [u8; 3] = [225, 45, 45];

/// The frame, `width` × `height` pixels, rows top to bottom, RGB bytes.
pub fn section_rgb(scene: &Scene, highlight: &[&str], width: usize, height: usize) -> Vec<u8> {
    let mut img = Canvas {
        px: vec![0; width * height * 3],
        width,
        height,
    };
    img.fill_rect(0.0, 0.0, width as f64, height as f64, GRASS);
    let road = &scene.road;
    let s0 = road.ramp_start();
    let sx = width as f64 / (road.section_end - s0);
    let w = road.lane_width;
    let lanes = f64::from(road.top_lane() - road.bottom_lane() + 1);
    let bottom = f64::from(road.bottom_lane()) * w;
    // The bottom lane's right edge at 80 % of the height, the top lane's left edge at 20 %.
    let sy = 0.6 * height as f64 / (lanes * w);
    let x = |s: f64| (s - s0) * sx;
    let y = |lateral: f64| 0.8 * height as f64 - (lateral - bottom + 0.5 * w) * sy;
    let band = |img: &mut Canvas, lane: i32, from: f64, to: f64| {
        let (top, bottom) = (
            y(f64::from(lane) * w + 0.5 * w),
            y(f64::from(lane) * w - 0.5 * w),
        );
        img.fill_rect(x(from), top, x(to), bottom, ASPHALT);
        img.fill_rect(x(from), top - 1.0, x(to), top + 1.0, MARKING);
        img.fill_rect(x(from), bottom - 1.0, x(to), bottom + 1.0, MARKING);
    };
    for lane in road.main_lane_range() {
        band(&mut img, lane, 0.0, road.section_end);
    }
    for z in &road.zones {
        band(&mut img, z.lane, z.ramp_start, z.end);
    }
    for v in &scene.vehicles {
        let colour = if highlight.contains(&&*v.id) {
            HIGHLIGHT
        } else if v.kind == Kind::Cav {
            CAV
        } else {
            HDV
        };
        let centre = f64::from(v.lane) * w + v.lateral;
        img.fill_rect(
            x(v.rear()),
            y(centre + 0.5 * v.width),
            x(v.front()),
            y(centre - 0.5 * v.width),
            colour,
        );
    }
    img.px
}

struct Canvas {
    px: Vec<u8>,
    width: usize,
    height: usize,
}

impl Canvas {
    /// Fills the pixels whose centres lie in [x0, x1) × [y0, y1), at least one pixel wide.
    fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, c: [u8; 3]) {
        let clamp = |v: f64, n: usize| v.round().clamp(0.0, n as f64) as usize;
        let (c0, r0) = (
            clamp(x0.min(x1), self.width),
            clamp(y0.min(y1), self.height),
        );
        let c1 = clamp(x0.max(x1), self.width).max((c0 + 1).min(self.width));
        let r1 = clamp(y0.max(y1), self.height).max((r0 + 1).min(self.height));
        for r in r0..r1 {
            for col in c0..c1 {
                let k = (r * self.width + col) * 3;
                self.px[k..k + 3].copy_from_slice(&c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::{Origin, VehicleState};

    #[test]
    fn vehicles_show_in_their_colours() {
        let cav = VehicleState::on_lane("c", Kind::Cav, Origin::Main, 200.0, 1, 30.0);
        let hdv = VehicleState::on_lane("h", Kind::Hdv, Origin::Main, 100.0, 2, 30.0);
        let scene = Scene::on_paper_road(0.0, vec![cav, hdv]);
        let (w, h) = (600, 150);
        let img = section_rgb(&scene, &["h"], w, h);
        assert_eq!(img.len(), w * h * 3);
        let count = |c: [u8; 3]| img.chunks(3).filter(|p| *p == c).count();
        assert!(
            count(CAV) > 4 && count(HIGHLIGHT) > 4,
            "{} {}",
            count(CAV),
            count(HIGHLIGHT)
        );
        assert_eq!(count(HDV), 0);
        assert!(count(ASPHALT) > count(CAV));
    }
}
