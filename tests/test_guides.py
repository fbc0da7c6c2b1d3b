"""The guides docs/adding-an-effect.md and docs/adding-a-joint.md name the files, types,
functions and tests a newcomer edits; each name they give must be in the tree as they say
(a moved file or a renamed function fails here until the guide follows), and every item of
the traits a new effect or joint implements without a default (`Declaration`, `ForceLaw`,
`JointType`, read from the Rust source) is named in the guide's walk through them."""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GUIDES = [ROOT / "docs" / "adding-an-effect.md", ROOT / "docs" / "adding-a-joint.md"]
CODE = re.compile(r"`([^`\n]+)`")
PATH = re.compile(r"^[\w./-]+\.(rs|py|pyi|md|toml)$")
# `Type`, `Type::item`, `function`, `function()`, `function(...)`, `macro!`.
NAME = re.compile(r"^([A-Za-z_][\w]*(?:::[A-Za-z_]\w*)*)(?:\(.*\)|!)?$")
# Words in backticks that are values, keys or Rust keywords, not names of code.
PLAIN = {"true", "false", "None", "Ok", "Err", "Some", "type", "name", "joints", "tau", "u8",
         "q", "v", "nv", "kind", "repr", "label", "build", "parameters", "apply", "key",
         "mod", "use", "Serialize", "Deserialize"}


def _guide_codes(page: Path) -> list[str]:
    text = page.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", "", text, flags=re.S)  # names, not code blocks
    return [c.strip() for c in CODE.findall(text)]


@cache
def _sources() -> dict[str, str]:
    """Every Rust and Python source of the tree, by path relative to the root."""
    out = {}
    for pattern in ("rust/**/*.rs", "python/**/*.py", "python/**/*.pyi", "tests/*.py"):
        for p in ROOT.glob(pattern):
            out[p.relative_to(ROOT).as_posix()] = p.read_text(encoding="utf-8")
    return out


def _is_hypothetical(code: str) -> bool:
    return "foo" in code.lower()


def _file_exists(path: str) -> bool:
    """A path from the root, or a file name (with folders) some source ends with."""
    return (ROOT / path).is_file() or any(s.endswith("/" + path) for s in _sources())


@cache
def _declared() -> frozenset[str]:
    """Every name the sources declare: Rust fns, types, consts, modules, macros, enum
    variants and struct fields; Python defs, classes and assigned names."""
    rust = re.compile(
        r"\b(?:fn|struct|enum|trait|type|const|static|mod)\s+(\w+)|macro_rules!\s*(\w+)"
        r"|^\s*(?:pub\s+)?(\w+)\s*[({,:]",
        re.M,
    )
    python = re.compile(r"^\s*(?:def|class)\s+(\w+)|^\s*(\w+)\s*[:=]", re.M)
    out = set()
    for path, text in _sources().items():
        pat = rust if path.endswith(".rs") else python
        for groups in pat.findall(text):
            out.update(g for g in groups if g)
    return frozenset(out)


def _cases():
    for page in GUIDES:
        for code in _guide_codes(page):
            if _is_hypothetical(code):
                continue
            if PATH.match(code):
                yield page.name, "file", code
            elif (m := NAME.match(code)) and code not in PLAIN:
                for part in m.group(1).split("::"):
                    if part not in PLAIN and len(part) > 2:
                        yield page.name, "name", part


CASES = sorted(set(_cases()))


def test_the_guides_name_enough_to_check():
    # A guide whose references were all lost to formatting would pass vacuously.
    for page in GUIDES:
        names = [c for c in CASES if c[0] == page.name]
        assert len([c for c in names if c[1] == "file"]) >= 5, page.name
        assert len([c for c in names if c[1] == "name"]) >= 10, page.name


@pytest.mark.parametrize("page, what, ref", CASES, ids=[f"{p}:{r}" for p, _, r in CASES])
def test_every_file_and_name_a_guide_gives_exists(page, what, ref):
    if what == "file":
        assert _file_exists(ref), f"{page} names the file {ref}, which is not in the tree"
    else:
        assert ref in _declared(), f"{page} names `{ref}`, which nothing in rust/, python/ declares"


def _required_items(path: str, trait: str) -> list[str]:
    """The functions and constants of `trait` (in `path`) that have no default: what an
    implementation must write."""
    text = (ROOT / path).read_text(encoding="utf-8")
    start = re.search(rf"pub trait {trait}\b[^{{]*\{{", text)
    assert start, f"no trait {trait} in {path}"
    i, depth, out = start.end(), 1, []
    while depth:
        m = re.compile(r"\b(fn|const)\s+(\w+)|[{}]").search(text, i)
        if m.group(0) == "{":
            depth, i = depth + 1, m.end()
        elif m.group(0) == "}":
            depth, i = depth - 1, m.end()
        else:
            end = re.compile(r"[;{=]").search(text, m.end())
            if depth == 1 and end.group(0) == ";":
                out.append(m.group(2))
            i = m.end()
    return out


SECTIONS = [
    # (guide, trait, its file, the guide's words before the list of the trait's items)
    ("adding-an-effect.md", "Declaration", "rust/effects/mod.rs", "impl Declaration for Foo"),
    ("adding-an-effect.md", "ForceLaw", "rust/effects/law.rs", "The law"),
    ("adding-a-joint.md", "JointType", "rust/joint/mod.rs", "impl JointType"),
]


@pytest.mark.parametrize("guide, trait, path, anchor", SECTIONS, ids=[s[1] for s in SECTIONS])
def test_a_guide_names_every_item_an_implementation_must_write(guide, trait, path, anchor):
    # What the compiler will ask of a new effect or joint, the guide says beforehand.
    text = (ROOT / "docs" / guide).read_text(encoding="utf-8")
    section = text[text.index(anchor):]
    section = section[: section.find("\n* **", 1) if "\n* **" in section[1:] else None]
    required = _required_items(path, trait)
    assert required, f"{trait}: no required item found (the parser lost the trait)"
    named = set(re.findall(r"`([A-Za-z_]\w*)", section))
    assert [r for r in required if r not in named] == [], f"{guide}: {trait}"
    count = re.search(rf"impl {trait}` \((\d+) methods\)", text)
    if count:  # the checklist's count
        assert int(count.group(1)) == len(required)


# --- The toy effect the effect guide shows whole --------------------------------------------
TOY = "rust/effects/toy_spring.rs"


def _rust_blocks(page: Path) -> list[str]:
    return re.findall(r"```rust\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)


def test_the_effect_guides_toy_is_the_file_the_crate_compiles():
    # The guide's block is the file, character for character: the file compiles in the
    # crate's test build and its unit test runs it through the registry, so a guide whose
    # code drifted from what compiles fails here.
    blocks = _rust_blocks(GUIDES[0])
    source = (ROOT / TOY).read_text(encoding="utf-8")
    assert source in blocks, f"docs/adding-an-effect.md: no ```rust block equal to {TOY}"
    assert "fn the_toy_spring_runs_through_the_registry" in source  # its test, in the block


def test_the_effect_guides_registry_lines_are_the_registrys():
    # The three lines that make the toy an effect (module, variant, registry line), each
    # under its `#[cfg(test)]`, are in rust/effects/mod.rs as the guide writes them.
    lines = [b for b in _rust_blocks(GUIDES[0]) if "Effect::ToySpring(e) => e" in b]
    assert len(lines) == 1, "the guide's block of registry lines"
    registry = [x.strip() for x in (ROOT / "rust/effects/mod.rs").read_text().splitlines()]
    wanted = [x.strip() for x in lines[0].splitlines() if x.strip()]
    assert len(wanted) == 6
    for attr, line in zip(wanted[::2], wanted[1::2]):
        assert attr == "#[cfg(test)]"
        at = [i for i, x in enumerate(registry) if x == line]
        assert at and registry[at[0] - 1] == attr, f"rust/effects/mod.rs lacks `{attr} {line}`"


# --- The toy joint the joint guide shows whole ----------------------------------------------
TOY_JOINT = "rust/joint/toy_cardan.rs"


def test_the_joint_guides_toy_is_the_file_the_crate_compiles():
    # As for the effect: the guide's block is the file the test build compiles, with the
    # unit tests that hold it to Rodrigues' rotation and to the quaternion ball joint.
    blocks = _rust_blocks(GUIDES[1])
    source = (ROOT / TOY_JOINT).read_text(encoding="utf-8")
    assert source in blocks, f"docs/adding-a-joint.md: no ```rust block equal to {TOY_JOINT}"
    assert "fn the_toy_cardan_joint_moves_as_the_ball_joint" in source


def test_the_joint_guides_dispatch_lines_are_the_dispatchs():
    # The module line, the variant and the dispatch arm, each under its `#[cfg(test)]`, are
    # in rust/joint/mod.rs as the guide writes them (each group of lines in a row).
    lines = [b for b in _rust_blocks(GUIDES[1]) if "Joint::ToyCardan => {" in b]
    assert len(lines) == 1, "the guide's block of dispatch lines"
    source = [x.strip() for x in (ROOT / "rust/joint/mod.rs").read_text().splitlines()]
    wanted = [x.strip() for x in lines[0].splitlines() if x.strip()]
    starts = [i for i, x in enumerate(wanted) if x == "#[cfg(test)]"]
    assert len(starts) == 3 and starts[0] == 0
    for a, b in zip(starts, starts[1:] + [len(wanted)]):
        group = wanted[a:b]
        at = [i for i in range(len(source)) if source[i : i + len(group)] == group]
        assert at, f"rust/joint/mod.rs lacks the lines {group}"


def test_no_match_on_joint_variants_outside_the_dispatch():
    # "A new joint: one file plus one dispatch arm": no exhaustive match on `Joint` outside
    # rust/joint/ (a match listing the variants with no catch-all arm) that a new variant
    # would break. Kind checks (`matches!`, `if let`, arms beside `_ =>`) may stay.
    variant = re.compile(r"\bJoint::(Revolute|Prismatic|SphericalZYZ|Spherical|Fixed|FreeFlyer)\b")
    offenders = []
    for path, text in _sources().items():
        if not path.startswith("rust/") or path.startswith("rust/joint/") or "/tests/" in path:
            continue
        for m in re.finditer(r"\bmatch\b[^{;]*\{", text):
            depth, i = 1, m.end()
            while depth and i < len(text):
                depth += {"{": 1, "}": -1}.get(text[i], 0)
                i += 1
            body = text[m.end() : i]
            arms = set(variant.findall(body))
            if len(arms) >= 5 and not re.search(r"^\s*_\s*=>", body, re.M):
                offenders.append(f"{path}: match at offset {m.start()}")
    assert offenders == []
