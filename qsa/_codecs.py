"""Result objects <-> (arrays, JSON metadata) for the files of :mod:`qsa.io`.

One encoder and one decoder per result kind (the layouts are documented in
:mod:`qsa.io`): a :class:`~qsa.Curve` and its energy, an
:class:`~qsa.equilibria.Equilibrium`, a :class:`~qsa.spectra.Spectrum` (with
the equilibrium it was computed at) and a :class:`~qsa.flows.FlowResult`
(from a result file or a checkpoint). Arrays keep their dtype (complex
eigenvalues, boolean masks) and are stored without pickle; everything else
goes to the JSON metadata. A member of a nested object is named
``<prefix>.<field>`` (``equilibrium.kappa``, ``kernel.rigid``).

The low-level file functions live in :mod:`qsa.npz`, which the library's own
layers (flows, sweeps, paper runs) use, so that this module can import the result
classes of all of them.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from qsa import energies
from qsa._version import __version__
from qsa.curve import Curve
from qsa.discretize import FiniteDifference, Fourier
from qsa.energies import DoubleWell
from qsa.equilibria import Equilibrium
from qsa.flows import CHA, FacetingFlow, FlowResult, SecondOrderFlow
from qsa.spectra import KernelReport, Spectrum

__all__ = ["KIND_EQUILIBRIUM", "KIND_SPECTRUM", "KIND_FLOW_RESULT", "KIND_FLOW_CHECKPOINT",
           "encode_equilibrium", "decode_equilibrium", "encode_spectrum", "decode_spectrum",
           "encode_flow_result", "decode_flow_result", "decode_flow_checkpoint",
           "energy_from_params", "model_from_metadata"]

KIND_EQUILIBRIUM = "qsa.equilibrium"
KIND_SPECTRUM = "qsa.spectrum"
KIND_FLOW_RESULT = "qsa.flow-result"
KIND_FLOW_CHECKPOINT = "qsa.flow-checkpoint"

#: The checkpoint's ``status`` word -> FlowResult status (success for all but "failed").
_CHECKPOINT_STATUS = {"finished": 0, "stopped": 1, "running": 1, "interrupted": 1,
                      "failed": -1, "max_steps": -2}


def _scalar(value):
    """A JSON-ready scalar (NumPy scalars converted), or the value unchanged."""
    return value.item() if isinstance(value, np.generic) else value


def _name(prefix, field):
    return f"{prefix}.{field}" if prefix else field


# ------------------------------------------------------------ curve and energy
def encode_curve(curve, prefix=""):
    """``(arrays, meta)`` of a :class:`~qsa.Curve`: ``kappa``, ``g``; grid, theta0, origin."""
    arrays = {_name(prefix, "kappa"): curve.kappa, _name(prefix, "g"): curve.g}
    meta = {"grid": {"kind": type(curve.grid).__name__, "N": int(curve.grid.N)},
            "theta0": float(curve.theta0), "origin": [float(v) for v in curve.origin]}
    return arrays, meta


def decode_curve(arrays, meta, prefix=""):
    """The :class:`~qsa.Curve` of :func:`encode_curve`."""
    grids = {"Fourier": Fourier, "FiniteDifference": FiniteDifference}
    kind = meta["grid"]["kind"]
    if kind not in grids:
        raise ValueError(f"unknown grid {kind!r}")
    grid = grids[kind](int(meta["grid"]["N"]))
    return Curve(arrays[_name(prefix, "kappa")], arrays[_name(prefix, "g")], grid,
                 meta["theta0"], tuple(meta["origin"]))


def energy_from_params(params):
    """The energy described by ``Energy.params()`` (a sum: the sum of its terms).

    Parameters
    ----------
    params : dict
        ``{"energy": class name, <scalar fields>}`` or ``{"energy": "sum", "terms": [...]}``.

    Returns
    -------
    Energy

    Examples
    --------
    >>> from qsa.energies import Faceting, Perimeter
    >>> E = Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
    >>> energy_from_params(E.params())
    Faceting(alpha=0.1, kstar=5.0) + Perimeter(beta=5.0, L_star=6.0)
    """
    name = params.get("energy")
    if name == "sum":
        terms = [energy_from_params(p) for p in params["terms"]]
        total = terms[0]
        for t in terms[1:]:
            total = total + t
        return total
    cls = getattr(energies, str(name), None)
    if not (isinstance(cls, type) and issubclass(cls, energies.Energy)):
        raise ValueError(f"unknown energy {name!r}")
    return cls(**{k: v for k, v in params.items() if k != "energy"})


def _energy_meta(energy, curve):
    """``energy.params()``, refused if it does not rebuild the same energy at ``curve``."""
    params = energy.params()
    try:
        rebuilt = energy_from_params(params)
        same = rebuilt.params() == params and np.isclose(
            rebuilt.energy(curve), energy.energy(curve), rtol=1e-13, atol=0.0)
    except (TypeError, ValueError):
        same = False
    if not same:
        raise ValueError(f"the energy {energy!r} cannot be stored in a file (it has parts, "
                         "such as a custom well, that its parameters do not describe)")
    return params


# ------------------------------------------------------------------- dataclasses
def _encode_fields(obj, prefix, skip=()):
    """Arrays and JSON scalars of a frozen dataclass's fields (``skip`` left out)."""
    arrays, meta = {}, {}
    for f in dataclasses.fields(obj):
        if f.name in skip:
            continue
        value = getattr(obj, f.name)
        if isinstance(value, np.ndarray):
            arrays[_name(prefix, f.name)] = value
        elif isinstance(value, tuple):
            meta[f.name] = [_scalar(v) for v in value]
        else:
            meta[f.name] = _scalar(value)
    return arrays, meta


def _decode_fields(cls, arrays, meta, prefix, **given):
    """Keyword arguments of ``cls`` from :func:`_encode_fields` output (plus ``given``)."""
    kwargs = dict(given)
    for f in dataclasses.fields(cls):
        if f.name in kwargs or not f.init:
            continue
        key = _name(prefix, f.name)
        if key in arrays:
            kwargs[f.name] = arrays[key]
        elif f.name in meta:
            value = meta[f.name]
            kwargs[f.name] = tuple(value) if isinstance(value, list) else value
    return cls(**kwargs)


# ------------------------------------------------------------------ equilibrium
def encode_equilibrium(eq, prefix=""):
    """``(arrays, fields)`` of an :class:`~qsa.equilibria.Equilibrium` (``extra`` left out).

    ``fields`` is the JSON of the curve's grid and frame, the energy, and the
    scalar fields; the file layout puts it under ``meta["equilibrium"]``.
    """
    arrays, meta = encode_curve(eq.curve, prefix)
    fields_arrays, fields_meta = _encode_fields(eq, prefix, skip=("curve", "energy", "extra"))
    arrays.update(fields_arrays)
    meta.update(fields_meta)
    meta["energy"] = _energy_meta(eq.energy, eq.curve)
    meta["params"] = {k: _scalar(v) for k, v in eq.params.items()}
    return arrays, meta


def decode_equilibrium(arrays, meta, prefix=""):
    """The :class:`~qsa.equilibria.Equilibrium` of :func:`encode_equilibrium`'s output."""
    return _decode_fields(Equilibrium, arrays, meta, prefix,
                          curve=decode_curve(arrays, meta, prefix),
                          energy=energy_from_params(meta["energy"]),
                          params=dict(meta["params"]))


# --------------------------------------------------------------------- spectrum
def encode_spectrum(spec, eq):
    """``(arrays, meta)`` of a :class:`~qsa.spectra.Spectrum` and the equilibrium it is of."""
    arrays, fields = _encode_fields(spec, "", skip=("kernel",))
    k_arrays, k_fields = _encode_fields(spec.kernel, "kernel")
    e_arrays, e_fields = encode_equilibrium(eq, "equilibrium")
    arrays.update(k_arrays)
    arrays.update(e_arrays)
    meta = {"kind": KIND_SPECTRUM, "version": __version__, "spectrum": fields,
            "kernel": k_fields, "equilibrium": e_fields}
    return arrays, meta


def decode_spectrum(arrays, meta):
    """The :class:`~qsa.spectra.Spectrum` of :func:`encode_spectrum`."""
    kernel = _decode_fields(KernelReport, arrays, meta["kernel"], "kernel")
    return _decode_fields(Spectrum, arrays, meta["spectrum"], "", kernel=kernel)


# ------------------------------------------------------------------------- flows
def model_from_metadata(meta):
    """The flow model (``CHA``, ``FacetingFlow``, ``SecondOrderFlow``) of ``system.metadata()``.

    Raises
    ------
    ValueError
        An unknown model, or a faceting flow with a custom well.
    """
    name = meta.get("model")
    if name == "CHA":
        return CHA(eps=meta["eps"], beta=meta["beta"], rho=meta["rho"], A0=meta["A0"],
                   l_star=meta["l_star"], a=meta["a"],
                   adhesion_method=meta.get("adhesion_method", "neighbours"),
                   force_normal=meta.get("force_normal", "unit"))
    if name == "FacetingFlow":
        if meta.get("well") not in (None, repr(DoubleWell(meta["kstar"]))):
            raise ValueError(f"a faceting flow with the well {meta['well']} cannot be rebuilt "
                             "from its file (only the default double well can)")
        return FacetingFlow(alpha=meta["alpha"], kstar=meta["kstar"], beta=meta["beta"],
                            L_star=meta["L_star"])
    if name == "SecondOrderFlow":
        energy = energy_from_params(meta["energy"])
        if "energy_repr" in meta and repr(energy) != meta["energy_repr"]:
            raise ValueError(f"the energy {meta['energy_repr']} cannot be rebuilt from its "
                             "parameters (only energies its parameters describe can)")
        return SecondOrderFlow(energy)
    raise ValueError(f"unknown flow model {name!r}")


def _system(model_meta, bound, x, y):
    return model_from_metadata(model_meta).setup(np.asarray(x), np.asarray(y), **bound)


def encode_flow_result(res):
    """``(arrays, meta)`` of a :class:`~qsa.flows.FlowResult` (its system by model + setup)."""
    system = res.system
    arrays, fields = _encode_fields(res, "", skip=("system",))
    arrays["x_setup"], arrays["y_setup"] = system.positions(system.y0)
    meta = {"kind": KIND_FLOW_RESULT, "version": __version__, "result": fields,
            "model": system.metadata(),
            "bound": system.bound_constants() if hasattr(system, "bound_constants") else {}}
    return arrays, meta


def decode_flow_result(arrays, meta):
    """The :class:`~qsa.flows.FlowResult` of :func:`encode_flow_result`."""
    system = _system(meta["model"], meta.get("bound", {}), arrays["x_setup"], arrays["y_setup"])
    return _decode_fields(FlowResult, arrays, meta["result"], "", system=system)


def decode_flow_checkpoint(arrays, meta, path):
    """The run so far, as a :class:`~qsa.flows.FlowResult`, from a ``solve_flow`` checkpoint.

    The snapshots and histories are those recorded up to the checkpoint; the final
    state is the integrator's. ``status`` follows the checkpoint's status word
    (``running``/``interrupted``: 1, stopped before ``t_final``).
    """
    system = _system(meta["model"], meta.get("bound", {}), arrays["x_setup"], arrays["y_setup"])
    scal = meta["integrator"]
    t, y = float(scal["t"]), np.asarray(arrays["y"], dtype=float)
    snap_t, snap_y = list(arrays["snap_t"]), list(arrays["snap_y"])
    snap_E, snap_L = list(arrays["snap_E"]), list(arrays["snap_L"])
    if not snap_t or snap_t[-1] != t:
        snap_t.append(t)
        snap_y.append(y)
        snap_E.append(system.energy(y))
        snap_L.append(system.length(y))
    word = meta.get("status", "running")
    status = _CHECKPOINT_STATUS.get(word, 1)
    X, Y = system.positions(y)
    return FlowResult(
        t=np.asarray(snap_t, dtype=float), states=np.asarray(snap_y).reshape(-1, system.size),
        energy=np.asarray(snap_E, dtype=float), length=np.asarray(snap_L, dtype=float),
        t_steps=arrays["step_t"], energy_steps=arrays["step_E"],
        length_steps=arrays["step_L"], success=status >= 0, status=status,
        message=f"Checkpoint {path} ({word}) at t = {t:.6g} of t_final = "
                f"{meta.get('t_final', float('nan')):.6g}.",
        n_steps=int(scal["n_steps"]), n_rejected=int(scal["n_rejected"]),
        n_newton=int(scal["n_iterations"]), n_lu=int(scal["n_factorizations"]),
        n_newton_failures=int(scal["n_newton_failures"]), checkpoint=str(path), x=X, y=Y,
        method=meta["options"]["method"], tol=float(meta["options"]["tol"]), system=system)
