//! The canvas (the window right of the panel) and its view of the world: zoom about the
//! cursor, pan, fit. Picking, adding and cutting all go through [`CanvasView::window_to_world`],
//! so they stay exact at every zoom and pan.

use super::events::PressedAt;
use bevy::camera::ScalingMode;
use bevy::input::mouse::{AccumulatedMouseScroll, MouseScrollUnit};
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::render::renderer::RenderAdapterInfo;
use bevy::render::view::Msaa;
use bevy::window::PrimaryWindow;
use bevy_egui::input::EguiWantsInput;

/// World margin shown around what is fitted, as a fraction of its size.
const MARGIN: f64 = 0.06;
/// Zoom limits, in logical pixels per metre.
const MIN_SCALE: f32 = 5.0;
const MAX_SCALE: f32 = 200_000.0;
/// Zoom factor per wheel notch.
const ZOOM_STEP: f32 = 1.2;

/// The current mapping between window (logical pixels, y down) and world (metres, y up).
#[derive(Resource, Debug, Clone, Copy)]
pub struct CanvasView {
    /// Width of the side panel, in logical pixels; the canvas is the rest of the window.
    pub panel_width: f32,
    /// Logical pixels per metre.
    pub scale: f32,
    /// The canvas centre in window coordinates: the window point of [`Self::world_center`].
    pub center: Vec2,
    /// The world point shown at the canvas centre.
    pub world_center: DVec2,
    /// The window size, in logical pixels.
    pub window: Vec2,
    /// While set, the view follows the window: it shows this world box (min, max), fitted.
    /// Zooming or panning clears it; F sets it to the scene.
    pub fit: Option<(DVec2, DVec2)>,
}

impl CanvasView {
    /// How far right of the window's middle the canvas's middle is, in logical pixels: the
    /// offset that centres a window-anchored overlay over the canvas.
    pub fn canvas_offset(&self) -> f32 {
        self.panel_width / 2.0
    }
}

impl Default for CanvasView {
    fn default() -> Self {
        CanvasView {
            panel_width: 0.0,
            scale: 500.0,
            center: Vec2::new(640.0, 400.0),
            world_center: DVec2::splat(0.5),
            window: Vec2::new(1280.0, 800.0),
            fit: Some(UNIT_SQUARE),
        }
    }
}

/// The unit square, which the view fits at start.
pub const UNIT_SQUARE: (DVec2, DVec2) = (DVec2::ZERO, DVec2::ONE);

impl CanvasView {
    pub fn window_to_world(&self, p: Vec2) -> DVec2 {
        let d = (p - self.center) / self.scale;
        self.world_center + DVec2::new(d.x as f64, -d.y as f64)
    }

    /// Is this window point on the canvas (not on the panel)?
    pub fn on_canvas(&self, p: Vec2) -> bool {
        p.x > self.panel_width
    }

    /// May a gesture start at this window point: on the canvas, and not over a window of
    /// egui's (the help overlay)?
    pub fn free_for_gesture(&self, p: Vec2, egui: &EguiWantsInput) -> bool {
        self.on_canvas(p) && !egui.wants_any_pointer_input()
    }

    /// Metres per logical pixel.
    pub fn pixel(&self) -> f64 {
        1.0 / self.scale as f64
    }

    /// The world box the window shows (min, max).
    pub fn visible(&self) -> (DVec2, DVec2) {
        let a = self.window_to_world(Vec2::new(0.0, self.window.y));
        let b = self.window_to_world(Vec2::new(self.window.x, 0.0));
        (a, b)
    }

    /// Zooms by `factor` keeping the world point under `cursor` where it is.
    pub fn zoom_about(&mut self, cursor: Vec2, factor: f32) {
        let at = self.window_to_world(cursor);
        self.scale = (self.scale * factor).clamp(MIN_SCALE, MAX_SCALE);
        let d = (cursor - self.center) / self.scale;
        self.world_center = at - DVec2::new(d.x as f64, -d.y as f64);
        self.fit = None;
    }

    /// Moves the view by a cursor displacement (window pixels): the world follows the cursor.
    pub fn pan(&mut self, delta: Vec2) {
        self.world_center -= DVec2::new(delta.x as f64, -delta.y as f64) * self.pixel();
        self.fit = None;
    }

    /// Lays the view out for the window: the canvas centre, and the fit when one is set.
    fn lay_out(&mut self, window: Vec2) {
        self.window = window;
        let canvas = Vec2::new((window.x - self.panel_width).max(1.0), window.y.max(1.0));
        self.center = Vec2::new(self.panel_width + canvas.x / 2.0, window.y / 2.0);
        if let Some((min, max)) = self.fit {
            let size = (max - min).max(DVec2::splat(1e-3)) * (1.0 + 2.0 * MARGIN);
            let scale = (canvas.x as f64 / size.x).min(canvas.y as f64 / size.y);
            self.scale = (scale as f32).clamp(MIN_SCALE, MAX_SCALE);
            self.world_center = (min + max) / 2.0;
        }
    }
}

/// The box F fits: the unit square and every particle.
pub fn scene_box(positions: &[DVec2]) -> (DVec2, DVec2) {
    positions
        .iter()
        .filter(|p| p.is_finite())
        .fold(UNIT_SQUARE, |(min, max), p| (min.min(*p), max.max(*p)))
}

pub fn spawn_camera(mut commands: Commands) {
    commands.spawn((
        Camera2d,
        Projection::Orthographic(OrthographicProjection {
            scaling_mode: ScalingMode::WindowSize,
            ..OrthographicProjection::default_2d()
        }),
    ));
}

/// Multisampling on a GPU, none on a software renderer (lavapipe, llvmpipe), where 4× MSAA
/// multiplies the rasterizer's work on the cores the simulation needs. Measured on the 64×64
/// cloth under Xvfb and lavapipe: 3.6–4.9 frames/s with MSAA, 8.8–10.2 without.
pub fn match_antialiasing(
    adapter: Res<RenderAdapterInfo>,
    mut cameras: Query<&mut Msaa, With<Camera2d>>,
) {
    let software = adapter.device_type == wgpu_types::DeviceType::Cpu;
    for mut msaa in &mut cameras {
        *msaa = if software { Msaa::Off } else { Msaa::Sample4 };
    }
}

/// Mouse wheel: zoom about the cursor (wheel up zooms in). Middle drag: pan.
pub fn zoom_and_pan(
    window: Single<&Window, With<PrimaryWindow>>,
    scroll: Res<AccumulatedMouseScroll>,
    pointer: Res<PressedAt>,
    buttons: Res<ButtonInput<MouseButton>>,
    egui: Res<EguiWantsInput>,
    mut view: ResMut<CanvasView>,
    mut panning: Local<bool>,
) {
    let layout = *view;
    let free = |p: Vec2| layout.free_for_gesture(p, &egui);
    if let Some(cursor) = window.cursor_position()
        && scroll.delta.y != 0.0
        && free(cursor)
    {
        let notches = match scroll.unit {
            MouseScrollUnit::Line => scroll.delta.y,
            MouseScrollUnit::Pixel => scroll.delta.y / 100.0,
        };
        view.zoom_about(cursor, ZOOM_STEP.powf(notches));
    }
    if pointer.middle.is_some_and(free) {
        *panning = true;
    }
    if *panning && pointer.middle_drag != Vec2::ZERO {
        view.pan(pointer.middle_drag);
    }
    if !buttons.pressed(MouseButton::Middle) {
        *panning = false;
    }
}

/// Lays the view out for the window and points the camera at it.
pub fn fit_camera(
    window: Single<&Window, With<PrimaryWindow>>,
    mut view: ResMut<CanvasView>,
    camera: Single<(&mut Projection, &mut Transform), With<Camera2d>>,
) {
    let size = Vec2::new(window.width(), window.height());
    let mut next = *view;
    next.lay_out(size);
    if next.scale != view.scale
        || next.center != view.center
        || next.world_center != view.world_center
        || next.window != view.window
    {
        *view = next;
    }
    let (mut projection, mut transform) = camera.into_inner();
    if let Projection::Orthographic(ortho) = &mut *projection {
        ortho.scale = 1.0 / view.scale;
    }
    // The camera looks at the world point under the window's centre.
    let at = view.window_to_world(size / 2.0);
    transform.translation = Vec3::new(at.x as f32, at.y as f32, 0.0);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Zooming keeps the world point under the cursor where it is; panning moves the world
    /// with the cursor; a fit shows its box whole.
    #[test]
    fn zoom_keeps_the_point_under_the_cursor_and_pan_follows_it() {
        let mut view = CanvasView {
            panel_width: 290.0,
            ..Default::default()
        };
        view.lay_out(Vec2::new(1280.0, 800.0));
        let cursor = Vec2::new(900.0, 250.0);
        let at = view.window_to_world(cursor);
        for factor in [1.2, 1.2, 0.5, 3.7] {
            view.zoom_about(cursor, factor);
            assert!(view.window_to_world(cursor).distance(at) < 1e-6);
        }
        assert!(view.fit.is_none(), "zooming leaves the fit");
        let before = view.window_to_world(Vec2::new(700.0, 500.0));
        view.pan(Vec2::new(-30.0, 12.0));
        let after = view.window_to_world(Vec2::new(700.0 - 30.0, 500.0 + 12.0));
        assert!(
            after.distance(before) < 1e-9,
            "the world follows the cursor"
        );
        view.fit = Some(UNIT_SQUARE);
        view.lay_out(Vec2::new(1000.0, 700.0));
        let (min, max) = view.visible();
        assert!(min.x < 0.0 && min.y < 0.0 && max.x > 1.0 && max.y > 1.0);
        assert!(view.window_to_world(Vec2::new(view.panel_width, 0.0)).x < 0.0);
    }

    /// An overlay anchored at the window's middle plus [`CanvasView::canvas_offset`] sits over
    /// the canvas's middle, whatever the panel's width (it was a fixed 140 px, half of a panel
    /// narrower than the 290 px one).
    #[test]
    fn the_canvas_offset_centres_an_overlay_over_the_canvas() {
        for panel_width in [0.0, 290.0, 412.5] {
            let mut view = CanvasView {
                panel_width,
                ..Default::default()
            };
            view.lay_out(Vec2::new(1280.0, 800.0));
            let canvas_middle = (panel_width + 1280.0) / 2.0;
            assert_eq!(640.0 + view.canvas_offset(), canvas_middle);
            assert_eq!(view.center.x, canvas_middle);
        }
    }
}
