//! Where a step's time goes: wall time per pass, kept only when asked for (`hooke run
//! --profile` calls [`enable`]; without it the marks are not in the schedule at all).
//!
//! A mark before the first pass and after each pass reads the clock; each pass is charged
//! the time since the mark before it. The passes' own run conditions still apply, so a pass
//! that does not run shows (almost) no time.

use super::sets::{PhysicsStep, StepSystems};
use bevy::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Seconds of wall time spent in each pass of the step, summed over the steps run.
#[derive(Resource, Debug, Default, Clone, Serialize, PartialEq)]
pub struct PassTimes {
    /// The force pass, s.
    pub forces: f64,
    /// The integrator's update, s.
    pub integrate: f64,
    /// Damping, s.
    pub damping: f64,
    /// Ground contact, s.
    pub ground: f64,
    /// The position update, s.
    pub advance: f64,
    /// The contact pass (obstacles, and the ground when contact is set), s.
    pub contact: f64,
    #[serde(skip)]
    mark: Option<Instant>,
}

impl PassTimes {
    /// All passes, s.
    pub fn total(&self) -> f64 {
        self.forces + self.integrate + self.damping + self.ground + self.advance + self.contact
    }
}

fn start(mut times: ResMut<PassTimes>) {
    times.mark = Some(Instant::now());
}

/// A mark that charges the time since the previous one to `pass`.
fn lap(pass: fn(&mut PassTimes) -> &mut f64) -> impl FnMut(ResMut<PassTimes>) {
    move |mut times: ResMut<PassTimes>| {
        let now = Instant::now();
        if let Some(mark) = times.mark {
            *pass(&mut times) += (now - mark).as_secs_f64();
        }
        times.mark = Some(now);
    }
}

/// Adds [`PassTimes`] and the marks around the step's sets to an app built with
/// [`super::SimPlugin`].
pub fn enable(app: &mut App) {
    app.init_resource::<PassTimes>();
    app.edit_schedule(PhysicsStep, |schedule| {
        schedule.add_systems((
            start.before(StepSystems::Forces),
            lap(|t| &mut t.forces)
                .after(StepSystems::Forces)
                .before(StepSystems::Integrate),
            lap(|t| &mut t.integrate)
                .after(StepSystems::Integrate)
                .before(StepSystems::Damping),
            lap(|t| &mut t.damping)
                .after(StepSystems::Damping)
                .before(StepSystems::Ground),
            lap(|t| &mut t.ground)
                .after(StepSystems::Ground)
                .before(StepSystems::Advance),
            lap(|t| &mut t.advance)
                .after(StepSystems::Advance)
                .before(StepSystems::Collide),
            lap(|t| &mut t.contact).after(StepSystems::Collide),
        ));
    });
}
