//! The frame's input events in the order they happened, for what a frame's end state cannot
//! tell: where a press happened, how far a pan went, how many times a key went down and which
//! modifiers were held when it did.

use bevy::input::ButtonState;
use bevy::input::keyboard::KeyboardInput;
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

/// One key going down, with the modifiers held at that moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyPress {
    pub key: KeyCode,
    pub shift: bool,
    pub ctrl: bool,
    /// The system's key repeat (the key held down), not a press of the user's.
    pub repeat: bool,
}

/// The frame's key presses, in order. `ButtonInput<KeyCode>` folds a frame's key events into
/// sets: two presses of one key in a frame count once, and a chord whose modifier goes up in
/// the same frame cannot say whether the modifier was down for the key. At 20–30 frames a
/// second a quick double ctrl+Z does both, so the shortcuts read these instead.
#[derive(Resource, Debug, Default)]
pub struct KeyPresses(pub Vec<KeyPress>);

/// What the replay carries from frame to frame: the cursor, the middle button, and which
/// modifier keys are down (left and right apart, so that letting go of one while the other is
/// held keeps the modifier).
#[derive(Debug, Default)]
pub struct Held {
    cursor: Option<Vec2>,
    middle_down: bool,
    keys: Vec<KeyCode>,
}

impl Held {
    fn any(&self, pair: [KeyCode; 2]) -> bool {
        self.keys.iter().any(|k| pair.contains(k))
    }

    /// Follows a key event: modifiers go up and down, other keys' presses are returned.
    fn key(&mut self, k: &KeyboardInput) -> Option<KeyPress> {
        const MODIFIERS: [KeyCode; 4] = [
            KeyCode::ShiftLeft,
            KeyCode::ShiftRight,
            KeyCode::ControlLeft,
            KeyCode::ControlRight,
        ];
        if MODIFIERS.contains(&k.key_code) {
            self.keys.retain(|&held| held != k.key_code);
            if k.state == ButtonState::Pressed {
                self.keys.push(k.key_code);
            }
            return None;
        }
        (k.state == ButtonState::Pressed).then(|| KeyPress {
            key: k.key_code,
            shift: self.any([KeyCode::ShiftLeft, KeyCode::ShiftRight]),
            ctrl: self.any([KeyCode::ControlLeft, KeyCode::ControlRight]),
            repeat: k.repeat,
        })
    }
}

/// Fills [`PressedAt`] and [`KeyPresses`] from the frame's window events.
pub fn track_presses(
    mut events: MessageReader<WindowEvent>,
    mut held: Local<Held>,
    mut pressed: ResMut<PressedAt>,
    mut keys: ResMut<KeyPresses>,
) {
    *pressed = PressedAt::default();
    keys.0.clear();
    for event in events.read() {
        match event {
            WindowEvent::CursorMoved(m) => {
                if held.middle_down
                    && let Some(prev) = held.cursor
                {
                    pressed.middle_drag += m.position - prev;
                }
                held.cursor = Some(m.position);
            }
            WindowEvent::MouseButtonInput(b) => match (b.button, b.state) {
                (MouseButton::Left, ButtonState::Pressed) => {
                    pressed.left = pressed.left.or(held.cursor);
                }
                (MouseButton::Middle, ButtonState::Pressed) => {
                    held.middle_down = true;
                    pressed.middle = pressed.middle.or(held.cursor);
                }
                (MouseButton::Middle, ButtonState::Released) => held.middle_down = false,
                _ => {}
            },
            WindowEvent::KeyboardInput(k) => keys.0.extend(held.key(k)),
            // The window lost focus: whatever was held may go up where we cannot see it.
            WindowEvent::KeyboardFocusLost(_) => held.keys.clear(),
            _ => {}
        }
    }
}

/// How long after the last input the card's state keeps coming back each tick.
const READ_AFTER_INPUT: std::time::Duration = std::time::Duration::from_secs(1);

/// Input in the window (the pointer, a button, the wheel, a key, a dropped file) asks for the
/// card's state each tick for the next second, while the steps run there with their state read
/// on demand: picking, dragging and editing then see the state of the last tick, as on the
/// CPU. A window nobody touches reads only the card's summary.
pub fn read_the_card_on_input(
    mut events: MessageReader<WindowEvent>,
    mut card: ResMut<crate::sim::gpu::CardStep>,
) {
    let input = events.read().any(|e| {
        matches!(
            e,
            WindowEvent::CursorMoved(_)
                | WindowEvent::MouseButtonInput(_)
                | WindowEvent::MouseWheel(_)
                | WindowEvent::KeyboardInput(_)
                | WindowEvent::FileDragAndDrop(_)
                | WindowEvent::TouchInput(_)
        )
    });
    if input {
        card.keep_reading(READ_AFTER_INPUT);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(key_code: KeyCode, state: ButtonState) -> KeyboardInput {
        KeyboardInput {
            key_code,
            logical_key: bevy::input::keyboard::Key::Unidentified(
                bevy::input::keyboard::NativeKey::Unidentified,
            ),
            state,
            text: None,
            repeat: false,
            window: Entity::PLACEHOLDER,
        }
    }

    /// Two ctrl+Z chords and a ctrl+shift+Z within one frame: three presses, each with the
    /// modifiers that were down for it; a Z after ctrl went up has none.
    #[test]
    fn chords_in_one_frame_keep_their_count_and_modifiers() {
        use ButtonState::{Pressed as Down, Released as Up};
        use KeyCode::*;
        let mut app = App::new();
        app.add_message::<WindowEvent>()
            .init_resource::<PressedAt>()
            .init_resource::<KeyPresses>()
            .add_systems(Update, track_presses);
        let stream = [
            (ControlLeft, Down),
            (KeyZ, Down),
            (KeyZ, Up),
            (ControlLeft, Up),
            (ControlLeft, Down),
            (KeyZ, Down),
            (KeyZ, Up),
            (ShiftRight, Down),
            (KeyZ, Down),
            (ShiftRight, Up),
            (ControlLeft, Up),
            (KeyZ, Down),
        ];
        for (k, s) in stream {
            app.world_mut()
                .write_message(WindowEvent::KeyboardInput(key(k, s)));
        }
        app.update();
        let got: Vec<(KeyCode, bool, bool)> = app
            .world()
            .resource::<KeyPresses>()
            .0
            .iter()
            .map(|p| (p.key, p.ctrl, p.shift))
            .collect();
        assert_eq!(
            got,
            [
                (KeyZ, true, false),
                (KeyZ, true, false),
                (KeyZ, true, true),
                (KeyZ, false, false)
            ]
        );
        // The next frame starts empty; a lost focus lets go of a held modifier.
        app.world_mut()
            .write_message(WindowEvent::KeyboardInput(key(ControlLeft, Down)));
        app.world_mut()
            .write_message(WindowEvent::KeyboardFocusLost(
                bevy::input::keyboard::KeyboardFocusLost,
            ));
        app.world_mut()
            .write_message(WindowEvent::KeyboardInput(key(KeyY, Down)));
        app.update();
        let presses = &app.world().resource::<KeyPresses>().0;
        assert_eq!(presses.len(), 1);
        assert!(!presses[0].ctrl);
    }
}
