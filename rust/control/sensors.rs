//! What a controller reads besides `q` and `v`: the actuators' joint torques and IMUs (a
//! frame fixed on a body: its accelerometer's specific force, gravity included, and its
//! angular velocity, in the frame's axes). Contact forces per point are the ground contacts'
//! own output (Python's `contact_forces`).
use crate::effects::Kind;
use crate::kinematics::{self, LinkState};
use crate::model::Model;
use crate::simulate::Dynamics;
use crate::support::error::{Error, Result};
use crate::support::spatial::{angular, linear, stack, Mat3, Vec3, Vec6};

/// An IMU: a frame on body `body` at `position` with axes `rotation` (columns: the sensor's
/// axes), both in the body's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Imu {
    pub body: usize,
    pub position: Vec3,
    pub rotation: Mat3,
}

/// Buffers of the sensor evaluations (allocated once).
pub struct SensorWork {
    links: Vec<LinkState>,
    /// Spatial accelerations `[ω̇; a_O]` of the links (world axes, the origin's acceleration).
    acc: Vec<Vec6>,
    vdot: Vec<f64>,
    forces: Vec<f64>,
}

impl SensorWork {
    pub fn new(model: &Model) -> Self {
        SensorWork {
            links: vec![LinkState::default(); model.links.len()],
            acc: vec![Vec6::zeros(); model.links.len()],
            vdot: vec![0.0; model.nv],
            forces: Vec::new(),
        }
    }
}

/// The torques-family effects' generalized forces plus the held torque control, into `out`.
pub(super) fn joint_torques(
    model: &Model,
    sys: &mut Dynamics<'_>,
    w: &mut SensorWork,
    t: f64,
    y: &[f64],
    out: &mut [f64],
) -> Result<()> {
    let (nq, nv) = (model.nq, model.nv);
    let (q, v) = y.split_at(nq);
    let kinds = sys.effects.kinds();
    w.forces.resize(kinds.len() * nv, 0.0);
    sys.effect_forces(t, q, v, &mut w.forces)
        .map_err(|m| Error::arg("sensors", "effects that evaluate at the state", m))?;
    out.fill(0.0);
    for (k, kind) in kinds.iter().enumerate() {
        if *kind == Kind::Torques {
            for (o, f) in out.iter_mut().zip(&w.forces[k * nv..(k + 1) * nv]) {
                *o += f;
            }
        }
    }
    for (o, u) in out.iter_mut().zip(&sys.control) {
        *o += u;
    }
    Ok(())
}

/// Each IMU's `[specific force; angular velocity]` (sensor axes) into `out` (6 per IMU).
pub(super) fn imu(
    model: &Model,
    sys: &mut Dynamics<'_>,
    w: &mut SensorWork,
    imus: &[Imu],
    t: f64,
    y: &[f64],
    out: &mut [f64],
) -> Result<()> {
    let nq = model.nq;
    let (q, v) = y.split_at(nq);
    sys.accelerations(t, q, v, &mut w.vdot)
        .map_err(|m| Error::arg("sensors", "effects that evaluate at the state", m))?;
    kinematics::positions(model, q, &mut w.links);
    kinematics::velocities(model, q, v, &mut w.links);
    link_accelerations(model, &w.links, &w.vdot, &mut w.acc);
    let g = sys.effects.gravity;
    for (k, s) in imus.iter().enumerate() {
        let body = model.bodies.get(s.body).ok_or_else(|| {
            Error::arg(
                format!("imu[{k}].body"),
                format!("a body index below {}", model.nbodies()),
                format!("{}", s.body),
            )
        })?;
        let place = kinematics::body_placement(model, &w.links, s.body);
        let axes = place.rotation * s.rotation;
        let (a, omega) = match body.link {
            Some(l) => {
                let (tw, acc) = (&w.links[l].twist, &w.acc[l]);
                let r = place.rotation * s.position + place.translation - w.links[l].origin;
                let (om, al) = (angular(tw), angular(acc));
                (linear(acc) + al.cross(&r) + om.cross(&om.cross(&r)), om)
            }
            None => (Vec3::zeros(), Vec3::zeros()),
        };
        let f = axes.transpose() * (a - g);
        let gyro = axes.transpose() * omega;
        out[6 * k..6 * k + 3].copy_from_slice(f.as_slice());
        out[6 * k + 3..6 * k + 6].copy_from_slice(gyro.as_slice());
    }
    Ok(())
}

/// `ṫ_i = A ṫ_λ + ξ_i + P_i v̇_i`: the links' angular accelerations and their origins'
/// accelerations (world axes) from the twists and `ξ` of [`kinematics::velocities`].
fn link_accelerations(model: &Model, links: &[LinkState], vdot: &[f64], acc: &mut [Vec6]) {
    for (i, l) in model.links.iter().enumerate() {
        let carried = match l.parent {
            Some(p) => {
                let (ap, r) = (acc[p], links[i].origin - links[p].origin);
                let al = angular(&ap);
                stack(&al, &(linear(&ap) + al.cross(&r)))
            }
            None => Vec6::zeros(),
        };
        let mut a = carried + links[i].xi;
        for k in 0..l.joint.nv() {
            a += links[i].s[k] * vdot[l.v_index + k];
        }
        acc[i] = a;
    }
}

/// IMUs as a caller lists them: `(body index, position (3,), rotation (3, 3))` each, in the
/// body's frame.
pub fn imus_arg<A: crate::support::args::Arg>(x: &A) -> std::result::Result<Vec<Imu>, A::Err> {
    use crate::support::args::{count, items, mat3, vec3};
    let expected = "(body index, position (3,), rotation (3, 3))";
    let one = |(k, item): (usize, A)| {
        let arg = format!("imu[{k}]");
        let [body, p, r] = <[A; 3]>::try_from(items(&item, &arg, expected)?)
            .map_err(|_| crate::support::error::Error::arg(&arg, expected, item.shown()))?;
        Ok(Imu {
            body: count(&body, &format!("{arg}.body"), "a body index")?,
            position: vec3(&p, &format!("{arg}.position"))?,
            rotation: mat3(&r, &format!("{arg}.rotation"))?,
        })
    };
    items(x, "imus", "a list of IMUs")?
        .into_iter()
        .enumerate()
        .map(one)
        .collect()
}
