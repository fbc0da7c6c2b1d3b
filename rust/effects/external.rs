//! External forces and wrenches on a body, the `external` family: a force `f` applied at a
//! point fixed in the body (given in the body's frame), plus an optional pure moment `m`,
//! constant or tabulated in time. `frame = World` (default): `f` and `m` have world
//! components; `frame = Body`: they turn with the body (a thruster). A body on a Fixed joint
//! is welded into its moving link: the point is carried into the link frame once, at setup.
//!
//! Evaluation needs only the link's orientation `R` (the wrench is taken about the link
//! origin): `[R p × f + m; f]`, with `R` composed along the link's ancestors, so a force on
//! link `i` costs O(depth of i) and nothing when undeclared.
use super::scene_writer as w;
use super::table::Table;
use super::{
    check_values, resolve_body, Context, Declaration, Fields, ForceLaw, JointRef, Kind, Matrix,
    Sign,
};
use super::{label_repr, Effect, TomlType};
use crate::model::Model;
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::{stack, Mat3, Vec3, Vec6};

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Frame {
    World,
    Body,
}

impl Frame {
    pub fn parse(s: &str, arg: &str) -> Result<Frame> {
        match s {
            "world" => Ok(Frame::World),
            "body" => Ok(Frame::Body),
            other => Err(Error::arg(
                arg,
                "\"world\" or \"body\"",
                format!("\"{other}\""),
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Frame::World => "world",
            Frame::Body => "body",
        }
    }
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ExternalLoad {
    Constant {
        force: Vec3,
        moment: Vec3,
    },
    /// Six columns: force x, y, z, then moment x, y, z.
    Tabulated(Table),
}

/// Keys of a `type = "external"` table.
const KEYS: &[&str] = &["name", "body", "point", "frame", "force", "moment", "time"];

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct External {
    pub name: Option<String>,
    pub body: JointRef,
    /// Point of application in the body frame.
    pub point: Vec3,
    pub frame: Frame,
    pub load: ExternalLoad,
}

impl External {
    pub fn constant(
        name: Option<String>,
        body: JointRef,
        point: Vec3,
        force: Vec3,
        moment: Vec3,
        frame: Frame,
    ) -> Result<External> {
        check_finite("point", point.as_slice())?;
        check_finite("force", force.as_slice())?;
        check_finite("moment", moment.as_slice())?;
        Ok(External {
            name,
            body,
            point,
            frame,
            load: ExternalLoad::Constant { force, moment },
        })
    }

    /// `force` and `moment` (either may be absent, not both): shape (N, 3), one row per time.
    pub fn tabulated(
        name: Option<String>,
        body: JointRef,
        point: Vec3,
        time: Vec<f64>,
        force: Option<Matrix>,
        moment: Option<Matrix>,
        frame: Frame,
    ) -> Result<External> {
        check_finite("point", point.as_slice())?;
        let n = time.len();
        if force.is_none() && moment.is_none() {
            return Err(Error::arg(
                "force",
                "a table of forces (N, 3) (or give moment)",
                "nothing",
            ));
        }
        let mut cols = [vec![0.0; 3 * n], vec![0.0; 3 * n]];
        for (slot, (arg, m)) in [("force", force), ("moment", moment)]
            .into_iter()
            .enumerate()
        {
            if let Some(m) = m {
                if m.rows != n || m.cols != 3 || m.one_d {
                    return Err(Error::arg(
                        arg,
                        format!("shape ({n}, 3): one row per time"),
                        m.shape(),
                    ));
                }
                check_values(arg, &m.values, Sign::Any)?;
                cols[slot] = m.values;
            }
        }
        let mut values = Vec::with_capacity(6 * n);
        for i in 0..n {
            values.extend_from_slice(&cols[0][3 * i..3 * i + 3]);
            values.extend_from_slice(&cols[1][3 * i..3 * i + 3]);
        }
        let table = Table::new(
            time,
            Matrix {
                values,
                rows: n,
                cols: 6,
                one_d: false,
            },
            "time",
            "force",
        )?;
        Ok(External {
            name,
            body,
            point,
            frame,
            load: ExternalLoad::Tabulated(table),
        })
    }

    pub(super) fn from_toml(f: &mut Fields<'_>) -> Result<External> {
        let name = f.string("name")?;
        let body = f.joints("body")?;
        let point = f.vec3("point")?.unwrap_or_else(Vec3::zeros);
        let frame = match f.string("frame")? {
            Some(s) => Frame::parse(&s, "frame")?,
            None => Frame::World,
        };
        let tabulated = f.has("time");
        let time = f.list("time")?;
        let body = match body.as_deref() {
            Some([b]) => b.clone(),
            _ => {
                return Err(Error::arg(
                    "body",
                    "one body name or index",
                    if body.is_none() { "nothing" } else { "a list" },
                ))
            }
        };
        if tabulated {
            let force = f.matrix("force")?;
            let moment = f.matrix("moment")?;
            let time = time.unwrap_or_default();
            External::tabulated(name, body, point, time, force, moment, frame)
        } else {
            let force = f.vec3("force")?;
            let moment = f.vec3("moment")?;
            if force.is_none() && moment.is_none() {
                return Err(Error::arg(
                    "force",
                    "a 3-vector (or give moment)",
                    "nothing",
                ));
            }
            External::constant(
                name,
                body,
                point,
                force.unwrap_or_else(Vec3::zeros),
                moment.unwrap_or_else(Vec3::zeros),
                frame,
            )
        }
    }
}

impl Declaration for External {
    fn to_toml(&self) -> Result<toml::Table> {
        let t = w::EffectTable::new("external", self.label())
            .set("body", w::joint_ref(&self.body))
            .set("point", w::vec3(&self.point))
            .set("frame", toml::Value::String(self.frame.name().into()));
        Ok(match &self.load {
            ExternalLoad::Constant { force, moment } => t
                .set("force", w::vec3(force))
                .set("moment", w::vec3(moment)),
            ExternalLoad::Tabulated(table) => {
                // Six columns: the force's three, then the moment's.
                let (mut force, mut moment) = (Vec::new(), Vec::new());
                for row in table.values().chunks(6) {
                    force.extend_from_slice(&row[..3]);
                    moment.extend_from_slice(&row[3..]);
                }
                t.set("time", w::numbers(table.time()))
                    .set("force", w::rows(&force, 3, false))
                    .set("moment", w::rows(&moment, 3, false))
            }
        }
        .done())
    }
    fn parameters(&self) -> &'static [&'static str] {
        &[]
    }
    fn with_parameter(&self, key: &str, _values: &[f64]) -> Result<Effect> {
        Err(Error::arg(
            "parameter",
            "none (an external load has no parameter to replace)",
            format!("'{key}'"),
        ))
    }
    fn repr(&self) -> String {
        let p = self.point;
        let rows = match &self.load {
            ExternalLoad::Constant { .. } => String::new(),
            ExternalLoad::Tabulated(t) => format!(", {} rows", t.len()),
        };
        format!(
            "ExternalForce(body={}, point=[{}, {}, {}], frame='{}'{rows}{})",
            self.body,
            p.x,
            p.y,
            p.z,
            self.frame.name(),
            label_repr(self.label()),
        )
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "external",
            keys: KEYS,
            parse: |_, f| External::from_toml(f).map(Effect::External),
        }];
        TYPES
    }
    fn kind(&self) -> Kind {
        Kind::External
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let b = resolve_body(model, &self.body, "body")?;
        let rec = &model.bodies[b];
        let link = rec.link.ok_or_else(|| {
            Error::arg(
                "body",
                "a body that can move",
                format!(
                    "body '{}', welded to the world (a force on it moves nothing)",
                    rec.name
                ),
            )
        })?;
        let mut path = Vec::new();
        let mut l = Some(link);
        while let Some(i) = l {
            path.push(i);
            l = model.links[i].parent;
        }
        path.reverse();
        Ok(Box::new(ExternalLaw {
            link,
            path,
            point: rec.in_link.act_point(&self.point),
            rotation: rec.in_link.rotation,
            frame: self.frame,
            load: self.load.clone(),
            hint: 0,
            row: [0.0; 6],
        }))
    }
}

pub struct ExternalLaw {
    link: usize,
    /// Links from the root to `link`.
    path: Vec<usize>,
    /// The point and the body's orientation in the link frame.
    point: Vec3,
    rotation: Mat3,
    frame: Frame,
    load: ExternalLoad,
    hint: usize,
    row: [f64; 6],
}

impl ForceLaw for ExternalLaw {
    fn writes_wrenches(&self) -> bool {
        true
    }

    #[inline]
    fn apply(
        &mut self,
        cx: &Context<'_>,
        _tau: &mut [f64],
        wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        let mut r = Mat3::identity();
        for &i in &self.path {
            let l = &cx.model.links[i];
            let (rq, _) = l
                .joint
                .transform(&cx.q[l.q_index..l.q_index + l.joint.nq()]);
            r = r * l.placement.rotation * rq;
        }
        let (mut f, mut m) = match &self.load {
            ExternalLoad::Constant { force, moment } => (*force, *moment),
            ExternalLoad::Tabulated(t) => {
                t.eval(cx.t, &mut self.hint, &mut self.row);
                let x = &self.row;
                (Vec3::new(x[0], x[1], x[2]), Vec3::new(x[3], x[4], x[5]))
            }
        };
        if self.frame == Frame::Body {
            let rb = r * self.rotation;
            f = rb * f;
            m = rb * m;
        }
        let arm = r * self.point;
        wrenches[self.link] += stack(&(arm.cross(&f) + m), &f);
        Ok(true)
    }
}
