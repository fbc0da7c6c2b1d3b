//! The stepping simulator's calls from a caller's arguments ([`Arg`]): read, checked and
//! done in one call each, so a binding only converts.
use super::sensors::imus_arg;
use super::{ControlKind, OwnedSimulator, Simulator, Stepping};
use crate::io::scene::Scene;
use crate::simulate::RunConfig;
use crate::support::args::{opt, vector, Arg};
use crate::support::error::Result;

impl OwnedSimulator {
    /// [`OwnedSimulator::of_scene`] from the caller's arguments: the run settings `given`
    /// (keyword, value; `None`: not given), the start, control period and whether to record,
    /// the `control` ("torque" or "pd") and the recorded times `t_eval`.
    pub fn from_args<A: Arg>(
        scene: &Scene,
        given: &[(&str, Option<&A>)],
        (t0, period, record): (f64, f64, bool),
        control: &A,
        t_eval: Option<&A>,
    ) -> std::result::Result<Self, A::Err> {
        let kind = ControlKind::from_arg(control)?;
        let call = RunConfig::from_call(None, given)?;
        let t_eval = opt(t_eval, |te| vector(te, "t_eval", None))?;
        let t_eval = t_eval.as_deref();
        let at = Stepping {
            t0,
            period,
            kind,
            record,
            t_eval,
        };
        Ok(OwnedSimulator::of_scene(scene, call, at)?)
    }
}

impl Simulator<'_> {
    /// [`Simulator::set_control`] with the caller's `control` (a 1-D array).
    pub fn set_control_arg<A: Arg>(&mut self, u: &A) -> std::result::Result<(), A::Err> {
        Ok(self.set_control(&vector(u, "control", None)?)?)
    }

    /// [`Simulator::set_state`] with the caller's `(q, v)`.
    pub fn set_state_arg<A: Arg>(&mut self, q: &A, v: &A) -> std::result::Result<(), A::Err> {
        let (q, v) = (vector(q, "q", None)?, vector(v, "v", None)?);
        Ok(self.set_state(&q, &v)?)
    }

    /// [`Simulator::joint_torques`] now, as a new vector (nv).
    pub fn torques_now(&mut self) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.nv()];
        self.joint_torques(&mut out)?;
        Ok(out)
    }

    /// [`Simulator::imu`] of the caller's IMUs now: 6 readings per IMU, and their count.
    pub fn imu_arg<A: Arg>(&mut self, imus: &A) -> std::result::Result<(Vec<f64>, usize), A::Err> {
        let list = imus_arg(imus)?;
        let mut out = vec![0.0; 6 * list.len()];
        self.imu(&list, &mut out)?;
        Ok((out, list.len()))
    }
}
