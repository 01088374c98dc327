//! Maps the unit square into the canvas (the window right of the panel), keeping its aspect.

use bevy::camera::ScalingMode;
use bevy::math::DVec2;
use bevy::prelude::*;
use bevy::render::renderer::RenderAdapterInfo;
use bevy::render::view::Msaa;
use bevy::window::PrimaryWindow;

/// World margin shown around the unit square.
const MARGIN: f32 = 0.06;

/// The current mapping between window (logical pixels, y down) and world (metres, y up).
#[derive(Resource, Debug, Clone, Copy)]
pub struct CanvasView {
    /// Width of the side panel, in logical pixels; the canvas is the rest of the window.
    pub panel_width: f32,
    /// Logical pixels per metre.
    pub scale: f32,
    /// Canvas centre in window coordinates; it shows the world point (0.5, 0.5).
    pub center: Vec2,
}

impl Default for CanvasView {
    fn default() -> Self {
        CanvasView {
            panel_width: 0.0,
            scale: 500.0,
            center: Vec2::new(640.0, 400.0),
        }
    }
}

impl CanvasView {
    pub fn window_to_world(&self, p: Vec2) -> DVec2 {
        let d = (p - self.center) / self.scale;
        DVec2::new(0.5 + d.x as f64, 0.5 - d.y as f64)
    }

    /// Is this window point on the canvas (not on the panel)?
    pub fn on_canvas(&self, p: Vec2) -> bool {
        p.x > self.panel_width
    }
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

/// Fits the camera so that the unit square (plus a margin) fills the canvas.
pub fn fit_camera(
    window: Single<&Window, With<PrimaryWindow>>,
    mut view: ResMut<CanvasView>,
    camera: Single<(&mut Projection, &mut Transform), With<Camera2d>>,
) {
    let (w, h) = (window.width(), window.height());
    let canvas_w = (w - view.panel_width).max(1.0);
    let scale = (canvas_w.min(h) / (1.0 + 2.0 * MARGIN)).max(1.0);
    let center = Vec2::new(view.panel_width + canvas_w / 2.0, h / 2.0);
    if view.scale != scale || view.center != center {
        view.scale = scale;
        view.center = center;
    }
    let (mut projection, mut transform) = camera.into_inner();
    if let Projection::Orthographic(ortho) = &mut *projection {
        ortho.scale = 1.0 / scale;
    }
    // The window centre sits (panel_width / 2) pixels left of the canvas centre.
    let x = 0.5 - view.panel_width / 2.0 / scale;
    transform.translation = Vec3::new(x, 0.5, 0.0);
}
