//! The frame's pointer events in the order they happened, for gestures that a frame's end
//! state cannot tell (where a press happened, how far a pan went).

use bevy::input::ButtonState;
use bevy::prelude::*;
use bevy::window::WindowEvent;

/// The frame's pointer events, replayed in order. A frame can bring a press and the moves
/// after it together (a quick press and drag, a slow frame): a press belongs where it
/// happened, not where the cursor is at the end of the frame, and a pan moves by the cursor's
/// path while the button was down.
#[derive(Resource, Debug, Default)]
pub struct PressedAt {
    /// Where the left button went down this frame, if it did.
    pub left: Option<Vec2>,
    /// Where the middle button went down this frame, if it did.
    pub middle: Option<Vec2>,
    /// How far the cursor moved this frame while the middle button was down.
    pub middle_drag: Vec2,
}

/// Fills [`PressedAt`] from the frame's window events.
pub fn track_presses(
    mut events: MessageReader<WindowEvent>,
    mut state: Local<(Option<Vec2>, bool)>,
    mut pressed: ResMut<PressedAt>,
) {
    let (cursor, middle_down) = &mut *state;
    *pressed = PressedAt::default();
    for event in events.read() {
        match event {
            WindowEvent::CursorMoved(m) => {
                if *middle_down && let Some(prev) = *cursor {
                    pressed.middle_drag += m.position - prev;
                }
                *cursor = Some(m.position);
            }
            WindowEvent::MouseButtonInput(b) => match (b.button, b.state) {
                (MouseButton::Left, ButtonState::Pressed) => {
                    pressed.left = pressed.left.or(*cursor);
                }
                (MouseButton::Middle, ButtonState::Pressed) => {
                    *middle_down = true;
                    pressed.middle = pressed.middle.or(*cursor);
                }
                (MouseButton::Middle, ButtonState::Released) => *middle_down = false,
                _ => {}
            },
            _ => {}
        }
    }
}
