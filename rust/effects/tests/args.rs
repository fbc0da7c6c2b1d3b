//! `effect` (Python's `pmd.Effect(type, **keys)`) with a stand-in for the binding's values:
//! TOML values, `None` for Python's `None`.
use super::*;
use crate::effects::toy_spring::ToySpring;
use crate::support::error::Result;

#[derive(Clone)]
struct V(Option<toml::Value>);

impl Arg for V {
    type Err = Error;
    fn absent(&self) -> bool {
        self.0.is_none()
    }
    fn is_bool(&self) -> bool {
        matches!(self.0, Some(toml::Value::Boolean(_)))
    }
    fn text(&self) -> Option<String> {
        self.0.as_ref()?.as_str().map(str::to_string)
    }
    fn int(&self) -> Int {
        match &self.0 {
            Some(toml::Value::Integer(i)) => Int::Value(*i),
            Some(toml::Value::Boolean(b)) => Int::Value(*b as i64),
            _ => Int::No,
        }
    }
    fn shown(&self) -> String {
        self.0.as_ref().map_or("None".into(), |v| v.to_string())
    }
    fn items(&self) -> Option<Result<Vec<V>>> {
        match &self.0 {
            Some(toml::Value::Array(a)) => Some(Ok(a.iter().map(|x| V(Some(x.clone()))).collect())),
            _ => None,
        }
    }
    fn real(&self, arg: &str) -> Result<f64> {
        match &self.0 {
            Some(toml::Value::Float(x)) => Ok(*x),
            Some(toml::Value::Integer(i)) => Ok(*i as f64),
            _ => Err(Error::arg(arg, "a real number", self.shown())),
        }
    }
    /// A number, a list of numbers, or a list of equal rows.
    fn array(&self, arg: &str) -> Result<(Vec<usize>, Vec<f64>)> {
        let Some(items) = self.items() else {
            return Ok((vec![], vec![self.real(arg)?]));
        };
        let mut shape = None;
        let mut values = Vec::new();
        let items = items?;
        for x in &items {
            let (s, v) = x.array(arg)?;
            assert!(shape.is_none() || shape.as_ref() == Some(&s), "ragged");
            shape = Some(s);
            values.extend(v);
        }
        let mut shape = shape.unwrap_or_default();
        shape.insert(0, items.len());
        Ok((shape, values))
    }
    fn wrong_type(&self, arg: &str, expected: &str) -> Error {
        Error::arg(arg, expected, self.shown())
    }
    fn get(&self, key: &str) -> Option<Option<V>> {
        match &self.0 {
            Some(toml::Value::Table(t)) => Some(t.get(key).map(|x| V(Some(x.clone())))),
            _ => None,
        }
    }
}

/// `ty`'s keyword arguments from a TOML snippet: their names and the mapping.
fn keywords(snippet: &str) -> (Vec<String>, V) {
    let t: toml::Table = snippet.parse().unwrap();
    (t.keys().cloned().collect(), V(Some(toml::Value::Table(t))))
}

fn construct(ty: &str, snippet: &str) -> Result<Effect> {
    let (keys, kw) = keywords(snippet);
    effect(ty, &keys, &kw)
}

/// A type without an arm of its own (the toy) is read by its scene-file parser.
#[test]
fn a_type_without_an_arm_is_read_as_its_scene_file_states_it() {
    let e = construct(
        "toy_spring",
        "stiffness = 4\njoints = [0, 'arm']\nname = 'k'",
    )
    .unwrap();
    let joints = vec![JointRef::Index(0), JointRef::Name("arm".into())];
    let toy = ToySpring::new(Some("k".into()), Some(joints), 4.0).unwrap();
    assert_eq!(e, Effect::ToySpring(toy));
    let err = |ty, s| construct(ty, s).unwrap_err().to_string();
    let unknown = err("toy_spring", "stifness = 4");
    assert!(
        unknown.starts_with(
            "stifness: expected a key of a \"toy_spring\" effect (type, name, joints, stiffness)"
        ),
        "{unknown}"
    );
    assert!(err("toy_spring", "stiffness = -1").starts_with("stiffness: "));
    assert!(err("toy_spring", "").starts_with("stiffness: "), "required");
    assert!(err("toy", "").starts_with("type: expected one of \"gravity\""));
}

/// Every built-in type's arm reads its keys as the scene file reads the same table: two
/// parsers of one declaration, which must agree.
#[test]
fn every_arm_agrees_with_the_scene_file() {
    let tables = [
        "type = 'gravity'\ng = [0, -9.8, 0]",
        "type = 'spring'\njoints = ['a', 1]\nstiffness = [1.0, 2.0]\nrest = 0.5\nname = 's'",
        "type = 'damper'\ndamping = 0.3",
        "type = 'friction'\njoints = 'a'\nfriction = 2.0\nv_eps = 0.01",
        "type = 'torque'\ntau = [1.0, 2.0]\nlimit = 'effort'",
        "type = 'tabulated_torque'\ntime = [0, 1]\nvalues = [[1, 2], [3, 4]]\nlimit = 5.0",
        "type = 'pd_torque'\njoints = 0\nkp = 10\nkd = 1\ntime = [0, 1]\nreference = [0, 1]",
        "type = 'external'\nbody = 'a'\nforce = [1, 2, 3]\npoint = [0, 0, 1]\nframe = 'body'",
        "type = 'external'\nbody = 1\nmoment = [[1, 2, 3], [4, 5, 6]]\ntime = [0, 1]",
        "type = 'point_spring'\nbody_a = 'a'\npoint_a = [0, 0, 0]\nbody_b = 'world'\npoint_b = [1, 0, 0]\nstiffness = 3\nrest_length = 0.5",
        "type = 'ground_contact'\npoints = [['a', [0, 0, 0]], [1, [0, 0, 1], 0.1]]\nnormal = [0, 0, 1]\nheight = 0\nexponent = 1.5\nfriction = 0.5\nv_eps = 0.001",
        "type = 'joint_limit'\nlower = -1\nupper = [1, 2]\nstiffness = 100\ndamping = 1",
    ];
    for table in tables {
        let mut t: toml::Table = table.parse().unwrap();
        let from_file = Effect::from_toml(&t).unwrap();
        let ty = t.remove("type").unwrap();
        let keys: Vec<String> = t.keys().cloned().collect();
        let kw = V(Some(toml::Value::Table(t)));
        let from_keywords = effect(ty.as_str().unwrap(), &keys, &kw).unwrap();
        assert_eq!(from_keywords, from_file, "{table}");
    }
}
