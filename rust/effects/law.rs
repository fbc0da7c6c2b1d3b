//! The engine's side of the effects: [`ForceLaw`], the one trait the engine calls, the resolved
//! set [`Effects`] the right-hand side composes, and [`Probe`] for per-effect forces.
use super::{Disabled, Effect, Kind};
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::recursive::{self, Data};
use crate::support::error::{Error, Result};
use crate::support::spatial::{Vec3, Vec6};

/// The state an effect is evaluated at.
#[derive(Clone, Copy)]
pub struct Context<'a> {
    pub model: &'a Model,
    pub t: f64,
    pub q: &'a [f64],
    pub v: &'a [f64],
}

/// One effect, resolved against a model: the only interface the engine knows.
pub trait ForceLaw: Send {
    /// A uniform acceleration field put on the base twist rate (gravity). The engine then
    /// never calls `apply` for this law in the right-hand side. Default: none.
    fn base_acceleration(&self) -> Option<Vec3> {
        None
    }
    /// Whether `apply` may write link wrenches (so the engine zeroes that buffer only then).
    fn writes_wrenches(&self) -> bool {
        false
    }
    /// Adds this effect's generalized joint forces at `cx` to `tau` (length nv) and its link
    /// wrenches `[moment about the link origin; force]` (world axes) to `wrenches`; returns
    /// whether it wrote a wrench. Must not allocate. An `Err` stops the integration.
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String>;
    /// Adds the derivatives of this law's joint forces `τ_e` (the `tau` part of `apply`) to
    /// `dq` (`∂τ_e/∂q`, columns in the tangent space as the dynamics derivatives,
    /// docs/derivatives.md) and `dv` (`∂τ_e/∂v`), both nv × nv; returns whether it did.
    /// `false` (the default) leaves them untouched and the caller differentiates the law's
    /// generalized force numerically (central differences), saying so in its result: external
    /// loads and Python callbacks. Must not allocate.
    fn add_derivatives(
        &mut self,
        _cx: &Context<'_>,
        _dq: &mut nalgebra::DMatrix<f64>,
        _dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        Ok(false)
    }
    /// Potential energy of a conservative effect (`links` holds positions at `cx.q`);
    /// `None` for the others.
    fn potential_energy(&self, _cx: &Context<'_>, _links: &[LinkState]) -> Option<f64> {
        None
    }
    /// The joints a PD law drives (0 for any other law): the length of its held reference.
    fn reference_joints(&self) -> usize {
        0
    }
    /// A PD law's reference held at `target` ([`ForceLaw::reference_joints`] values, zero
    /// reference rate) instead of its table; `None`: the table again. Must not allocate
    /// once a target was held.
    fn hold_reference(&mut self, _target: Option<&[f64]>) {}
}

pub(super) struct Item {
    label: String,
    kind: Kind,
    pub(super) law: Box<dyn ForceLaw>,
    /// Evaluated in the right-hand side (false for base-acceleration laws).
    pub(super) in_rhs: bool,
}

/// Names an effect output may not take (they are keys of the energy dictionary).
pub const RESERVED_LABELS: [&str; 2] = ["kinetic", "total"];

/// The declared, enabled effects of a scene, resolved against its model.
pub struct Effects {
    /// Sum of the enabled uniform gravities (zero when none).
    pub gravity: Vec3,
    pub(super) items: Vec<Item>,
    rhs_items: usize,
    rhs_wrenches: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            gravity: Vec3::zeros(),
            items: Vec::new(),
            rhs_items: 0,
            rhs_wrenches: false,
        }
    }
}

impl Effects {
    /// No effect at all: free motion.
    pub fn none() -> Self {
        Effects::default()
    }

    /// Resolves `specs` against `model`, leaving out the `disabled` families. Errors name
    /// `{list}[k].field` (`list` is `effects` for Python, `effect` in a scene file).
    pub fn new(model: &Model, specs: &[Effect], disabled: Disabled, list: &str) -> Result<Self> {
        let mut set = Effects::none();
        // Labels: the user's names first (unique, not reserved), then the family names,
        // numbered from the second of a family on (`springs`, `springs_2`, ...).
        let mut labels: Vec<Option<String>> = vec![None; specs.len()];
        for (k, s) in specs.iter().enumerate() {
            if let Some(l) = s.label() {
                let arg = format!("{list}[{k}].name");
                if l.trim().is_empty() || RESERVED_LABELS.contains(&l) {
                    return Err(Error::arg(
                        arg,
                        "a non-empty name other than 'kinetic' and 'total'",
                        format!("'{l}'"),
                    ));
                }
                if labels.iter().flatten().any(|x| x == l) {
                    return Err(Error::arg(
                        arg,
                        "a name no other effect has",
                        format!("'{l}' again"),
                    ));
                }
                labels[k] = Some(l.to_string());
            }
        }
        for (k, s) in specs.iter().enumerate() {
            if labels[k].is_none() {
                let base = s.kind().name();
                let mut n = 1;
                let mut l = base.to_string();
                while labels.iter().flatten().any(|x| *x == l) {
                    n += 1;
                    l = format!("{base}_{n}");
                }
                labels[k] = Some(l);
            }
        }
        for (k, (s, label)) in specs.iter().zip(labels).enumerate() {
            // Resolve even disabled effects, so a scene is valid or not whatever is switched off.
            let law = s
                .build(model)
                .map_err(|e| e.in_arg(&format!("{list}[{k}]")))?;
            if disabled.contains(s.kind()) {
                continue;
            }
            let in_rhs = match law.base_acceleration() {
                Some(g) => {
                    set.gravity += g;
                    false
                }
                None => true,
            };
            if in_rhs {
                set.rhs_items += 1;
                set.rhs_wrenches |= law.writes_wrenches();
            }
            set.items.push(Item {
                label: label.unwrap_or_default(),
                kind: s.kind(),
                law,
                in_rhs,
            });
        }
        Ok(set)
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
    /// Output names of the enabled effects, in declaration order.
    pub fn labels(&self) -> Vec<String> {
        self.items.iter().map(|i| i.label.clone()).collect()
    }
    pub fn kinds(&self) -> Vec<Kind> {
        self.items.iter().map(|i| i.kind).collect()
    }

    /// The right-hand side's composition: overwrites `tau` with the sum of the joint forces
    /// of the enabled effects (gravity excepted: it rides on the base acceleration) and, when
    /// any effect writes wrenches, `wrenches` with theirs; returns whether it wrote wrenches.
    /// With no such effect it touches nothing (`tau` is expected zero then).
    #[inline]
    pub fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        if self.rhs_items == 0 {
            return Ok(false);
        }
        tau.fill(0.0);
        if self.rhs_wrenches {
            wrenches.fill(Vec6::zeros());
        }
        let mut wrote = false;
        for item in self.items.iter_mut().filter(|i| i.in_rhs) {
            wrote |= item.law.apply(cx, tau, wrenches)?;
        }
        Ok(wrote)
    }

    /// Whether [`Effects::apply`] writes joint forces (some enabled effect besides gravity).
    pub fn applies_in_rhs(&self) -> bool {
        self.rhs_items > 0
    }

    /// The joints the enabled PD laws drive, in effect order (each law's own joints in its
    /// order): the length of a PD target ([`Effects::hold_pd_targets`]).
    pub fn pd_joints(&self) -> usize {
        self.items.iter().map(|i| i.law.reference_joints()).sum()
    }

    /// Holds the enabled PD laws' references at `targets` (their joints in
    /// [`Effects::pd_joints`] order), or, `None`, gives them their tables back. The caller
    /// checks the length.
    pub fn hold_pd_targets(&mut self, targets: Option<&[f64]>) {
        let mut at = 0;
        for item in self.items.iter_mut() {
            let n = item.law.reference_joints();
            if n > 0 {
                item.law.hold_reference(targets.map(|t| &t[at..at + n]));
                at += n;
            }
        }
    }

    /// Sum of the potential energies (gravity, springs); `links` holds positions at `cx.q`.
    pub fn potential_energy(&self, cx: &Context<'_>, links: &[LinkState]) -> f64 {
        self.items
            .iter()
            .filter_map(|i| i.law.potential_energy(cx, links))
            .sum()
    }

    /// `(label, V)` of every conservative effect.
    pub fn potentials(&self, cx: &Context<'_>, links: &[LinkState]) -> Vec<(String, f64)> {
        self.items
            .iter()
            .filter_map(|i| {
                i.law
                    .potential_energy(cx, links)
                    .map(|v| (i.label.clone(), v))
            })
            .collect()
    }
}

/// Workspace for evaluating effects one by one (per-effect generalized forces and power):
/// wrenches become joint forces through the inverse dynamics at rest, `τ_e = −ID(q, 0, 0)`.
pub struct Probe {
    data: Data,
    zeros: Vec<f64>,
    pub(super) tau: Vec<f64>,
    pub(super) id_out: Vec<f64>,
    pub(super) wrenches: Vec<Vec6>,
}

impl Probe {
    pub fn new(model: &Model) -> Self {
        Probe {
            data: Data::new(model),
            zeros: vec![0.0; model.nv],
            tau: vec![0.0; model.nv],
            id_out: vec![0.0; model.nv],
            wrenches: vec![Vec6::zeros(); model.links.len()],
        }
    }

    /// `ID(q, 0, 0)` into `id_out`: the joint forces that hold the model at rest at `cx.q`
    /// against gravity `g` and, `with_wrenches`, the link wrenches in `wrenches`.
    pub(super) fn inverse_at_rest(&mut self, cx: &Context<'_>, g: &Vec3, with_wrenches: bool) {
        recursive::inverse_dynamics(
            cx.model,
            &mut self.data,
            cx.q,
            &self.zeros,
            &self.zeros,
            g,
            with_wrenches.then_some(&self.wrenches[..]),
            &mut self.id_out,
        );
    }

    /// Generalized force of each enabled effect at `cx`, row-major `len × nv` into `out`
    /// (gravity's included: `Nᵀ f^G`).
    pub fn forces(
        &mut self,
        effects: &mut Effects,
        cx: &Context<'_>,
        out: &mut [f64],
    ) -> std::result::Result<(), String> {
        let nv = cx.model.nv;
        for (k, item) in effects.items.iter_mut().enumerate() {
            let row = &mut out[k * nv..(k + 1) * nv];
            if let Some(g) = item.law.base_acceleration() {
                self.inverse_at_rest(cx, &g, false);
                for (r, x) in row.iter_mut().zip(&self.id_out) {
                    *r = -x;
                }
                continue;
            }
            self.tau.fill(0.0);
            self.wrenches.fill(Vec6::zeros());
            let wrote = item.law.apply(cx, &mut self.tau, &mut self.wrenches)?;
            row.copy_from_slice(&self.tau);
            if wrote {
                self.inverse_at_rest(cx, &Vec3::zeros(), true);
                for (r, x) in row.iter_mut().zip(&self.id_out) {
                    *r -= x;
                }
            }
        }
        Ok(())
    }
}
