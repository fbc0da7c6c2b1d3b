//! The stepping simulator's calls from a caller's arguments ([`Arg`]): read, checked and
//! done in one call each, so a binding only converts.
use super::sensors::imus_arg;
use super::{ControlKind, OwnedSimulator, Simulator, Stepping};
use crate::io::scene::Scene;
use crate::simulate::config_args::mapped;
use crate::simulate::RunConfig;
use crate::support::args::{flag, opt, vector, Arg};
use crate::support::error::Result;

/// The keywords of the stepping simulator: the run settings it takes, then its own.
const KEYS: [&str; 12] = [
    "method",
    "rtol",
    "atol",
    "dt",
    "disable",
    "first_step",
    "max_step",
    "t_eval",
    "control_period",
    "control",
    "record",
    "t0",
];

impl OwnedSimulator {
    /// [`OwnedSimulator::of_scene`] from the caller's keywords `settings` (a mapping; a
    /// `None` value: not given): the run settings (the first 7 of [`KEYS`]), the recorded
    /// times `t_eval`, the `control_period` (0.001 s), the `control` ("torque", the default,
    /// or "pd"), whether to `record` (true) and the start `t0` (0). A keyword not in
    /// [`KEYS`] is the binding's type error (as an unexpected keyword argument).
    pub fn from_call<A: Arg>(
        scene: &Scene,
        settings: Option<&A>,
    ) -> std::result::Result<Self, A::Err> {
        let given = mapped(settings);
        if let Some((key, x)) = given.iter().find(|(k, _)| !KEYS.contains(&k.as_str())) {
            return Err(x.wrong_type(key, &format!("a keyword of Simulator: {}", KEYS.join(", "))));
        }
        let get = |key: &str| {
            given
                .iter()
                .find(|(k, x)| k == key && !x.absent())
                .map(|(_, x)| x)
        };
        let run = given
            .iter()
            .filter(|(k, _)| KEYS[..7].contains(&k.as_str()));
        let call = RunConfig::from_args(run.map(|(k, x)| (k.as_str(), x)))?;
        let real = |key, default| opt(get(key), |x| x.real(key)).map(|x| x.unwrap_or(default));
        let kind = opt(get("control"), ControlKind::from_arg)?;
        let t_eval = opt(get("t_eval"), |te| vector(te, "t_eval", None))?;
        let at = Stepping {
            t0: real("t0", 0.0)?,
            period: real("control_period", 0.001)?,
            kind: kind.unwrap_or(ControlKind::Torque),
            record: opt(get("record"), |x| flag(x, "record"))?.unwrap_or(true),
            t_eval: t_eval.as_deref(),
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
