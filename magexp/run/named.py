"""An estimator by its config name: ``conf/estimator/<name>.yaml`` composed (:mod:`magexp.run.compose`) and built
(:func:`magexp.run.runner.build`), for the callers that name one in code (the calibration API, its
closed-form reference fit, the cross-table and the peers' benchmark)."""

from __future__ import annotations

from omegaconf import OmegaConf

from magexp.errors import MagexpError, raise_if_stopped
from magexp.run.compose import check_choice, compose_config
from magexp.run.override_errors import bad_value
from magexp.run.runner import build


def estimator_named(name: str, **overrides):
    """The estimator of ``conf/estimator/<name>.yaml`` with ``overrides`` (its options: ``n_iterations=3``...),
    built by :func:`magexp.run.runner.build` from the config composed as every config is
    (:func:`compose_config`, the calibration's primary config ``conf/calibrate.yaml``).

    Raises
    ------
    MagexpError
        An unknown name or option."""
    check_choice("estimator", name)
    node = compose_config([f"estimator={name}"], config_name="calibrate").estimator
    unknown = [key for key in overrides if key not in node]
    if unknown:
        options = ", ".join(str(k) for k in node if not str(k).startswith("_") and k != "name")
        raise MagexpError(f"{unknown[0]}={overrides[unknown[0]]!r} is not allowed: estimator {name!r} has no option "
                          f"{unknown[0]!r} (options: {options})")
    try:
        node = OmegaConf.merge(node, overrides)
    except Exception as exc:  # the schema refused a value's type
        raise_if_stopped()
        key = str(getattr(exc, "full_key", "") or "").removeprefix("estimator.")
        key = key if key in overrides else next(iter(overrides))
        raise bad_value(key, repr(overrides[key]), exc) from None
    return build(node, f"estimator {name!r}")
