"""Every scenario and estimator config is typed: a value of the wrong type for any of its numeric keys is
refused when the config is composed, in one line naming the key (issue 35), before anything is built.

The cases are generated from the configs themselves (every numeric key of every composed config), so
a config or a key added untyped fails here."""

import os
import subprocess
import sys

import pytest
import yaml
from hydra.utils import get_class
from omegaconf import DictConfig, ListConfig, OmegaConf

from magexp.errors import MagexpError
from magexp.paths import CONF, EXPERIMENTS
from magexp.run import compose
from magexp.run.compose import compose_config, hydra_compose, options, schema_of

GROUPS = ("scenario", "estimator")


def _numeric(ref_type) -> bool:
    """Whether a node's declared type is an int or a float (also ``Optional``)."""
    return ref_type in (int, float) or any(a in (int, float) for a in getattr(ref_type, "__args__", ()))


def numeric_keys(node, prefix: str) -> list[tuple[str, str]]:
    """``(dotted key, wrong value)`` of every key of ``node`` typed as a number: a scalar gets ``abc``, a list of
    numbers ``[abc]``, a list of lists ``[[abc]]``."""
    out = []
    for key in node:
        child, where = node._get_node(key), f"{prefix}.{key}"
        if isinstance(child, DictConfig):
            out += numeric_keys(child, where)
        elif isinstance(child, ListConfig) and not child._is_none():
            depth, element = 1, child._metadata.element_type
            while element is not None and getattr(element, "__origin__", None) is list:
                depth, element = depth + 1, element.__args__[0]
            if _numeric(element):
                out.append((where, "[" * depth + "abc" + "]" * depth))
        elif not isinstance(child, ListConfig) and _numeric(child._metadata.ref_type):
            out.append((where, "abc"))
    return out


CONFIGS = [(group, name) for group in GROUPS for name in options(group)]


def named_by_artifacts(group: str) -> set:
    """The configs of ``group`` that the artifacts of ``experiments/`` name (``group=name`` in a base, a case or
    a grid): they must all exist, however many there are."""
    found = set()
    for path in EXPERIMENTS.glob("*/*.yaml"):
        spec = yaml.safe_load(path.read_text()) or {}
        overrides = [str(o).lstrip("?") for o in spec.get("base", []) + [o for c in spec.get("cases", []) for o in c]]
        found |= {o.split("=", 1)[1] for o in overrides if o.split("=", 1)[0] == group}
        found |= {str(v) for v in (spec.get("grid") or {}).get(group, [])}
    return found


def _first_of_each_group(configs) -> list:
    """``configs`` as parameters: the first config of each group in make test, the others in make test-full. Every
    schema is derived alike (every config typed by its class: test_every_config_is_typed_by_its_class, in make
    test); the first scenario's keys hold numbers, lists of numbers and a list of lists of them."""
    groups, out = set(), []
    for group, name in configs:
        out.append(pytest.param(group, name, id=name, marks=[] if group not in groups else [pytest.mark.full]))
        groups.add(group)
    return out


def test_every_config_is_typed_by_its_class():
    """Every config of ``conf/scenario/`` and ``conf/estimator/`` (counted from the folders, never pinned: adding
    one needs no test edit; every scenario and estimator an artifact names among them) has its class's schema."""
    for group in GROUPS:
        assert [name for g, name in CONFIGS if g == group] == sorted(p.stem for p in (CONF / group).glob("*.yaml"))
        assert named_by_artifacts(group) <= set(options(group)), group
    for group, name in CONFIGS:
        node = compose_config([f"{group}={name}"])[group]
        assert OmegaConf.get_type(node) is schema_of(get_class(node._target_)), (group, name)


@pytest.mark.parametrize("group, name", _first_of_each_group(CONFIGS))
def test_a_wrong_type_for_any_numeric_key_is_refused_at_compose(group, name):
    """Every numeric key of the config (from Hydra's compose of it): ``key=abc`` (``[abc]`` for a list of
    numbers) is refused by the composer in one line naming it."""
    keys = numeric_keys(hydra_compose((f"{group}={name}",))[group], group)
    assert keys or name in ("ellipsoid", "ls")  # their one key is their name
    wrong = []
    for key, value in keys:
        try:
            compose_config([f"{group}={name}", f"{key}={value}"])
            wrong.append(f"{key}={value}: composed")
        except MagexpError as exc:
            if "\n" in str(exc) or not str(exc).startswith(f"{key}={value} is not allowed"):
                wrong.append(str(exc))
    assert not wrong, wrong


def test_a_typo_in_a_nested_strategy_node_names_the_keys_that_exist():
    with pytest.raises(MagexpError, match=r"estimator.velocity has no key 'start' \(keys: _target_, c1, c2, inertia\)"):
        compose_config(["estimator=pso", "estimator.velocity.inertai.start=0.5"])


FULL = pytest.mark.full  # a fresh interpreter each (~1.2 s CPU): one in make test, the rest in make test-full


@pytest.mark.parametrize("args", [
    ["scenario=ding2024_exp1", "estimator=pso", "estimator.n_particles=abc", "seed=0"],
    pytest.param(["estimator=ipso", "estimator.velocity.c1.start=[1]"], marks=FULL),
    pytest.param(["scenario=real_qmc5883l", "estimator=lm", "scenario.offset_width=wide"], marks=FULL),
    pytest.param(["scenario=yuan2018_mode1", "estimator=rdpso", "estimator.velocity.alpha.rate=fast"], marks=FULL),
    pytest.param(["scenario=yan2022_sim", "estimator=kf", "estimator.n_steps=1.5"], marks=FULL),
], ids=lambda a: " ".join(a))
def test_a_wrong_type_on_the_command_line_is_one_line_exit_2_and_nothing_written(tmp_path, args):
    env = {**os.environ, "MAGEXP_CACHE": str(tmp_path / "cache" / "runs")}
    work = tmp_path / "work"
    work.mkdir()
    proc = subprocess.run([sys.executable, "-m", "magexp", *args], cwd=work, env=env, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: "), proc.stderr
    assert args[-2 if args[-1] == "seed=0" else -1].split("=")[0] in proc.stderr
    assert not any(work.iterdir()) and not (tmp_path / "cache").exists()
