//! A scene's parts as a binding hands them over (`Scene(model, q0, v0, effects, ...)` and
//! `scene.replace(...)` in Python): checked here, once, as a scene file's are.
use std::sync::Arc;

use super::{Scene, Settings};
use crate::effects::args::{effect_list, EffectArg};
use crate::effects::{fill_model_limits, Disabled, Effects};
use crate::model::Model;
use crate::support::args::{given, opt, vector};
use crate::support::error::Error;

impl Scene {
    /// A scene of `model` at its neutral configuration, at rest, with no effects and no
    /// settings of its own.
    pub fn of_model(model: Arc<Model>) -> Scene {
        Scene {
            name: "scene".into(),
            description: String::new(),
            q0: model.neutral(),
            v0: vec![0.0; model.nv],
            model,
            effects: Vec::new(),
            settings: Settings::default(),
        }
    }

    /// A copy with what is given replaced and everything else kept: the model (of this
    /// scene's sizes), the effects (a list, [`effect_list`]; a joint limit's missing bounds and
    /// a torque's `"effort"` the model's; checked against the model), the start state (`q0`
    /// and `v0` checked, `q0` normalised), the name and description; `settings` replace the
    /// scene's. Errors name the argument.
    pub fn replaced<A: EffectArg>(
        &self,
        model: Option<Arc<Model>>,
        [effects, q0, v0]: [Option<&A>; 3],
        (name, description): (Option<String>, Option<String>),
        settings: Settings,
    ) -> Result<Scene, A::Err> {
        let effects = given(effects).map(effect_list).transpose()?;
        let mut s = Scene {
            settings,
            ..self.clone()
        };
        s.name = name.unwrap_or(s.name);
        s.description = description.unwrap_or(s.description);
        if let Some(m) = model {
            let (nq, nv) = (s.model.nq, s.model.nv);
            if (m.nq, m.nv) != (nq, nv) {
                let expected = format!("a model with nq = {nq}, nv = {nv} (this scene's)");
                let got = format!("nq = {}, nv = {}", m.nq, m.nv);
                return Err(Error::arg("model", expected, got).into());
            }
            s.model = m;
        }
        let m = &s.model;
        if let Some(list) = effects {
            s.effects = list;
            fill_model_limits(m, &m.records.joints, &mut s.effects, "effects")?;
        }
        // Joint and body names, table widths and effect names must fit the model.
        Effects::new(m, &s.effects, Disabled::none(), "effects")?;
        s.q0 = opt(q0, |q| vector(q, "q0", Some(m.nq)))?.unwrap_or(s.q0);
        s.v0 = opt(v0, |v| vector(v, "v0", Some(m.nv)))?.unwrap_or(s.v0);
        m.check_state(&s.q0, Some(&s.v0))
            .map_err(|e| e.map_arg(|a| format!("{a}0")))?;
        m.normalize(&mut s.q0);
        Ok(s)
    }

    /// `Scene(name='...', nbodies=..., nq=..., nv=..., effects=[...])`, Python's `repr`.
    pub fn repr(&self) -> String {
        let effects: Vec<&str> = self.effects.iter().map(|e| e.name()).collect();
        format!(
            "Scene(name='{}', nbodies={}, nq={}, nv={}, effects=[{}])",
            self.name,
            self.model.nbodies(),
            self.model.nq,
            self.model.nv,
            effects.join(", ")
        )
    }
}
