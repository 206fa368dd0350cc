"""Pseudo-equilibria of Filippov systems: rest points of a sliding motion on a switching surface.

On a surface ``h(x) = 0`` whose two fields both push into it, the state slides with Filippov's convex
combination ``f_s = (1 - a) f_minus + a f_plus``, the weight ``a = h_x f_minus / (h_x f_minus - h_x f_plus)``
chosen so that ``f_s`` is tangent to the surface.  A pseudo-equilibrium is a point of the surface where
``f_s = 0``: both fields there are anti-parallel.  It is a point of the sliding region when ``0 < a < 1``
(both fields push into the surface); its stability in the sliding motion is that of ``f_s`` restricted
to the surface.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from saltation._moved import forward_names
from saltation.engine.flow import Flow
from saltation.errors import ModelError
from saltation.model.system import PiecewiseSystem
from saltation.orbits.equilibria import EquilibriumProblem
from saltation.orbits.problem import newton
from saltation.orbits.records import BranchPoint, Evaluation


@dataclass(frozen=True)
class PseudoEquilibrium:
    """A rest point of a sliding motion.

    Attributes
    ----------
    state : ndarray, shape (n,)
        The point, on the surface.
    surface : str
    modes : (str, str)
        The modes on the surface's negative (``h < 0``) and positive side.
    weights : (float, float)
        ``(1 - a, a)``: the weights of the two modes' fields in the sliding field, which vanishes there.
    eigenvalues : ndarray, shape (n - 1,), complex
        Of the sliding field restricted to the surface (its Jacobian on the tangent space): the point's
        stability in the sliding motion (stable when every real part is negative).
    admissible : bool
        Whether it lies in the sliding region (``0 < a < 1``: both fields push into the surface); a
        point with ``a`` outside is virtual.
    residual : float
        ``|f_s|`` there.
    """

    state: np.ndarray
    surface: str
    modes: tuple[str, str]
    weights: tuple[float, float]
    eigenvalues: np.ndarray
    admissible: bool
    residual: float

    @property
    def stable(self) -> bool:
        """Admissible and attracting in the sliding motion."""
        return bool(self.admissible and np.all(self.eigenvalues.real < 0))

    @property
    def isolated(self) -> bool:
        """False where the sliding field's Jacobian on the surface has an eigenvalue 0 (to 1e-9 of the largest):
        the point then lies on a continuum of pseudo-equilibria, as on the sticking set of a friction
        oscillator on a resting ground, where the sliding field vanishes identically, and it is neither
        stable nor unstable along the continuum."""
        if self.eigenvalues.size == 0:
            return True
        scale = 1.0 + float(np.max(np.abs(self.eigenvalues)))
        return bool(np.all(np.abs(self.eigenvalues) > 1e-9 * scale))

    def __repr__(self) -> str:
        x = ", ".join(f"{v:.8g}" for v in self.state)
        how = ("virtual" if not self.admissible else "stable" if self.stable else
               "unstable" if self.isolated else "not isolated: on a continuum of pseudo-equilibria")
        return (f"PseudoEquilibrium(on {self.surface}, x=[{x}], weights={self.weights[0]:.6g}/{self.weights[1]:.6g}, "
                f"{how})")


def find_pseudo_equilibrium(
    system: PiecewiseSystem | Flow,
    surface: str,
    state0: Sequence[float],
    *,
    parameters: Mapping[str, float] | np.ndarray | None = None,
    tol: float = 1e-12,
    max_iter: int = 30,
) -> PseudoEquilibrium:
    """A pseudo-equilibrium on ``surface`` near ``state0``, by Newton on ``(1 - a) f_minus + a f_plus = 0``,
    ``h = 0`` in the unknowns ``(x, a)``.

    The two modes are those on either side of the surface at ``state0`` (the model's initial-mode rule
    a little off the surface along ``h_x``); their fields' Jacobians are the model's exact ones.

    Parameters
    ----------
    system : PiecewiseSystem or Flow
        An autonomous model.
    surface : str
        The switching surface.
    state0 : array_like, shape (n,)
        A guess.
    parameters : mapping or ndarray, optional
        Parameter values (the model's defaults otherwise).
    tol : float
        Newton stops when ``|r| <= tol (1 + |x|)``: positive and finite.
    max_iter : int
        The most Newton steps, a non-negative integer.

    Returns
    -------
    PseudoEquilibrium

    Raises
    ------
    ModelError
        If the model is forced, the surface unknown, the guess of the wrong size or not finite, ``tol`` not
        positive and finite, ``max_iter`` not a non-negative integer, or the same mode lies on both sides of
        the surface at the guess; or if both fields vanish at the point found (to ``tol (1 + |x|)``): the
        sliding weight is undefined there (the point is an equilibrium of both modes, not of a sliding motion).
    ConvergenceError
        If Newton does not converge (with the residual history), or its Jacobian is singular.

    References
    ----------
    A. F. Filippov (1988), *Differential Equations with Discontinuous Righthand Sides*, Kluwer.
    Yu. A. Kuznetsov, S. Rinaldi and A. Gragnani (2003), "One-parameter bifurcations in planar Filippov
    systems", International Journal of Bifurcation and Chaos 13.
    """
    flow = system if isinstance(system, Flow) else Flow(system)
    model = flow.system
    if not model.is_autonomous:
        raise ModelError(f"model {model.name!r} is forced: it has no pseudo-equilibria (its fields depend on time)")
    if surface not in model.surface_names:
        raise ModelError(f"surface {surface!r} does not exist; surfaces are {list(model.surface_names)}")
    x = np.asarray(state0, dtype=float).reshape(-1)
    if x.shape != (model.n,):
        raise ModelError(f"the guess must have {model.n} components, got {x.shape[0]}")
    if not np.all(np.isfinite(x)):
        raise ModelError(f"the guess is not finite: {x.tolist()}")
    try:
        tol_ok = not isinstance(tol, bool) and math.isfinite(float(tol)) and float(tol) > 0.0
    except (TypeError, ValueError):
        tol_ok = False
    if not tol_ok:
        raise ModelError(f"tol must be positive and finite (Newton stops when |r| <= tol (1 + |x|)), got {tol!r}")
    tol = float(tol)
    try:
        iter_ok = not isinstance(max_iter, bool) and int(max_iter) == max_iter and max_iter >= 0
    except (TypeError, ValueError, OverflowError):
        iter_ok = False
    if not iter_ok:
        raise ModelError(f"max_iter must be a non-negative integer (the Newton steps), got {max_iter!r}")
    p = flow.parameters(parameters)
    minus, plus = _sides(flow, surface, x, p)
    a = sliding_weight(flow, surface, minus, plus, x, p)
    a = 0.5 if not math.isfinite(a) else a
    n = model.n

    def equations(u: np.ndarray):
        x, a = u[:n], float(u[n])
        fm, fp = flow.vector_field(minus, 0.0, x, p), flow.vector_field(plus, 0.0, x, p)
        jm, jp = flow.vector_field_jacobian(minus, 0.0, x, p), flow.vector_field_jacobian(plus, 0.0, x, p)
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = (1.0 - a) * jm + a * jp
        J[:n, n] = fp - fm
        J[n, :n] = flow.indicator_gradient(surface, 0.0, x, p)[0]
        return np.append((1.0 - a) * fm + a * fp, flow.indicator(surface, 0.0, x, p)), J, None

    solved = newton(equations, np.append(x, a), tol=tol, max_iter=int(max_iter), what=f"pseudo-equilibrium on {surface!r}",
                    size=lambda u: float(np.linalg.norm(u[:n])))
    x, a, history = solved.u[:n].copy(), float(solved.u[n]), solved.residuals
    _check_weight_defined(flow, surface, minus, plus, x, p, tol * (1.0 + float(np.linalg.norm(x))))
    eigenvalues = _sliding_eigenvalues(flow, surface, minus, plus, x, p)
    return PseudoEquilibrium(state=x, surface=surface, modes=(model.mode_names[minus], model.mode_names[plus]),
                             weights=(1.0 - a, a), eigenvalues=eigenvalues, admissible=bool(0.0 < a < 1.0),
                             residual=history[-1])


def sliding_weight(flow: Flow, surface: str, minus: int, plus: int, x: np.ndarray, p: np.ndarray) -> float:
    """The weight ``a`` of the positive side's field in Filippov's sliding combination at ``x``.

    Parameters
    ----------
    flow : Flow
    surface : str
    minus, plus : int
        The modes on the surface's negative and positive side.
    x : ndarray, shape (n,)
    p : ndarray
        Parameter values.

    Returns
    -------
    float
        ``h_x f_minus / (h_x f_minus - h_x f_plus)``, which makes the combination tangent to the surface
        (``nan`` where both normal components are equal).
    """
    hx = flow.indicator_gradient(surface, 0.0, x, p)[0]
    gm = float(hx @ flow.vector_field(minus, 0.0, x, p))
    gp = float(hx @ flow.vector_field(plus, 0.0, x, p))
    return gm / (gm - gp) if gm != gp else math.nan


def _sides(flow: Flow, surface: str, x: np.ndarray, p: np.ndarray) -> tuple[int, int]:
    """The modes on the negative and positive side of the surface at ``x``."""
    hx = flow.indicator_gradient(surface, 0.0, x, p)[0]
    size = float(np.linalg.norm(hx))
    if size == 0.0:
        raise ModelError(f"surface {surface!r} has no gradient at {x.tolist()}: no sides to tell apart")
    h = flow.indicator(surface, 0.0, x, p)
    d = hx / size
    offset = 1e-7 * (1.0 + float(np.linalg.norm(x)))
    base = x - (h / size) * d  # onto the surface (to first order)
    minus = flow.initial_mode(base - offset * d, p)
    plus = flow.initial_mode(base + offset * d, p)
    if minus == plus:
        name = flow.system.mode_names[minus]
        raise ModelError(f"mode {name!r} lies on both sides of surface {surface!r} at {x.tolist()}: no sliding there")
    return minus, plus


def _check_weight_defined(flow: Flow, surface: str, minus: int, plus: int, x: np.ndarray, p: np.ndarray,
                          small: float) -> None:
    """Raise where both fields vanish at ``x`` (to ``small``): every weight makes the sliding field vanish there."""
    fm, fp = flow.vector_field(minus, 0.0, x, p), flow.vector_field(plus, 0.0, x, p)
    if max(float(np.linalg.norm(fm)), float(np.linalg.norm(fp))) <= small:
        names = flow.system.mode_names
        raise ModelError(
            f"both fields vanish here: the sliding weight is undefined at x = {x.tolist()} on surface {surface!r} "
            f"(an equilibrium of both modes {names[minus]!r} and {names[plus]!r} on the surface, not a rest point of a "
            f"sliding motion)")


def _sliding_eigenvalues(flow: Flow, surface: str, minus: int, plus: int, x: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Eigenvalues of the sliding field's Jacobian on the surface's tangent space at ``x`` (central
    differences of the sliding field along an orthonormal basis of the tangent space, steps 1e-6)."""
    n = flow.system.n
    hx = flow.indicator_gradient(surface, 0.0, x, p)[0]
    _, _, vt = np.linalg.svd(hx[None, :])
    tangent = vt[1:].T  # (n, n - 1): the null space of h_x

    def sliding(y: np.ndarray) -> np.ndarray:
        a = sliding_weight(flow, surface, minus, plus, y, p)
        return (1.0 - a) * flow.vector_field(minus, 0.0, y, p) + a * flow.vector_field(plus, 0.0, y, p)

    if n == 1:
        return np.zeros(0, dtype=complex)
    step = 1e-6 * (1.0 + float(np.linalg.norm(x)))
    columns = [(sliding(x + step * t) - sliding(x - step * t)) / (2 * step) for t in tangent.T]
    restricted = tangent.T @ np.column_stack(columns)
    if not np.all(np.isfinite(restricted)):  # both fields' normal components equal next to x: no sliding field there
        _check_weight_defined(flow, surface, minus, plus, x, p, 1e3 * np.finfo(float).eps * (1.0 + float(np.linalg.norm(x))))
        raise ModelError(f"the sliding weight is undefined next to x = {x.tolist()} on surface {surface!r}: both fields "
                         f"have the same component normal to it there (both tangent to it, or both vanish)")
    return np.sort_complex(np.linalg.eigvals(restricted).astype(complex))




class PseudoEquilibriumProblem(EquilibriumProblem):
    """Pseudo-equilibria on a surface, in the continuation protocol: the unknowns are ``u = (x, a)``, the
    equations ``(1 - a) f_minus + a f_plus = 0`` and ``h = 0`` (exact Jacobians from the model).

    A branch of them is an equilibrium branch: each point's ``multipliers`` are the sliding field's
    eigenvalues on the surface, and it is stable when it lies in the sliding region (``0 < a < 1``) and
    they all have negative real parts.

    Parameters
    ----------
    flow : Flow
        The compiled flow of an autonomous model.
    surface : str
        The switching surface.
    modes : (str, str)
        The modes on its negative and positive side (see :func:`find_pseudo_equilibrium`).
    parameters : mapping or ndarray, optional
        Parameter values (the model's defaults otherwise).
    continuation_parameter : str, optional
        Name of the parameter ``lam``.

    Raises
    ------
    ModelError
        If the model is forced, or a surface, mode or parameter name is unknown.
    """

    def __init__(self, flow: Flow, surface: str, modes: tuple[str, str],
                 parameters: Mapping[str, float] | np.ndarray | None = None, *, continuation_parameter: str | None = None):
        super().__init__(flow, modes[0], parameters, continuation_parameter=continuation_parameter)
        if surface not in self.system.surface_names:
            raise ModelError(f"surface {surface!r} does not exist; surfaces are {list(self.system.surface_names)}")
        self.surface = surface
        self.minus, self.plus = (self.system.mode_index(m) for m in modes)

    @property
    def dimension(self) -> int:
        return self.system.n + 1

    def evaluate(self, u: np.ndarray, lam: float | None = None, *, need_lam: bool = True) -> Evaluation:
        """The sliding combination and the indicator at ``u = (x, a)``, with their Jacobians.

        Parameters
        ----------
        u : ndarray, shape (n + 1,)
        lam : float, optional
            Value of the continuation parameter.
        need_lam : bool
            Compute ``jac_lam`` too.

        Returns
        -------
        Evaluation
        """
        p = self.parameters_at(lam)
        n = self.system.n
        x, a = np.asarray(u[:n], dtype=float), float(u[n])
        flow = self.flow
        fm, fp = flow.vector_field(self.minus, 0.0, x, p), flow.vector_field(self.plus, 0.0, x, p)
        hx, _, hp = flow.indicator_gradient(self.surface, 0.0, x, p)
        residual = np.append((1.0 - a) * fm + a * fp, flow.indicator(self.surface, 0.0, x, p))
        J = np.zeros((n + 1, n + 1))
        J[:n, :n] = (1.0 - a) * flow.vector_field_jacobian(self.minus, 0.0, x, p) + a * flow.vector_field_jacobian(
            self.plus, 0.0, x, p)
        J[:n, n] = fp - fm
        J[n, :n] = hx
        jl = None
        if need_lam and lam is not None:
            k = self.lam_index
            jl = np.append((1.0 - a) * flow.vector_field_parameters(self.minus, 0.0, x, p)[:, k]
                           + a * flow.vector_field_parameters(self.plus, 0.0, x, p)[:, k], hp[k])
        return Evaluation(residual=residual, jac_u=J, jac_lam=jl)

    def describe(self, u: np.ndarray, lam: float | None, ev: Evaluation) -> BranchPoint:
        """A solved pseudo-equilibrium for a branch: its state, and the sliding eigenvalues as multipliers.

        Parameters
        ----------
        u : ndarray, shape (n + 1,)
        lam : float or None
        ev : Evaluation

        Returns
        -------
        BranchPoint
            Stable when admissible (``0 < a < 1``) and every eigenvalue has a negative real part.
        """
        n = self.system.n
        x, a = np.array(u[:n], dtype=float), float(u[n])
        eig = _sliding_eigenvalues(self.flow, self.surface, self.minus, self.plus, x, self.parameters_at(lam))
        eig = eig[np.lexsort((-eig.imag, -eig.real))]
        return BranchPoint(parameter=math.nan if lam is None else float(lam), state=x, period=float("nan"),
                           amplitude=float(abs(x[0])), half_peak_to_peak=0.0, multipliers=eig,
                           stable=bool(0.0 < a < 1.0 and np.all(eig.real < 0)), event_labels=())

    def solve(self, x0: Sequence[float], lam: float | None = None, *, tol: float = 1e-12, max_iter: int = 30):
        """The pseudo-equilibrium near ``x0`` at ``lam`` (:func:`find_pseudo_equilibrium`).

        Parameters
        ----------
        x0 : sequence of float
        lam : float, optional
        tol : float
        max_iter : int

        Returns
        -------
        PseudoEquilibrium
            Its ``state`` and ``weights`` make the continuation's first unknowns (:meth:`unknowns`).

        Raises
        ------
        ConvergenceError
            If Newton does not converge.
        """
        return find_pseudo_equilibrium(self.flow, self.surface, x0, parameters=self.parameters_at(lam), tol=tol,
                                       max_iter=max_iter)

    @staticmethod
    def unknowns(point: PseudoEquilibrium) -> np.ndarray:
        """The continuation's unknowns ``(x, a)`` of a pseudo-equilibrium."""
        return np.append(point.state, point.weights[1])


__all__ = ["PseudoEquilibrium", "PseudoEquilibriumProblem", "find_pseudo_equilibrium", "sliding_weight"]


# names the module held in release 0.1 and no longer imports: found where they live now, until 0.3.0
__getattr__ = forward_names(__name__, ('saltation.errors',))
