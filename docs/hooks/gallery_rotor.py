"""Gallery figure: the Neimark-Sacker curve of a Jeffcott rotor against a snubber ring, and its 1:1 resonance.

Not a hook of its own: ``docs/hooks/gallery.py`` imports :func:`figure_neimark_sacker` and computes it like its
other figures (in a child process, at every build; nothing is checked in).  The model is the one of
``tests/special_points/test_neimark_sacker_curves.py``, written here as the page writes it (:func:`rotor`): an
isotropic rotor without gravity, strong contact friction of the backward sense (``mu < 0``), ``zeta = 0.2``,
``beta = 3``, ``rho = 0.3``.  Computed from scratch:

* the branch of contact whirls over ``omega`` from 1.25, its Neimark-Sacker point, and the Neimark-Sacker curve
  in ``(omega, mu)`` by ``follow_locus`` (its neutral-saddle continuation past the 1:1 resonance drawn apart);
* the branch over ``omega`` downwards to its fold, and the fold curve in ``(omega, mu)``;
* the closed forms (numpy and scipy only): the whirls in contact all round are circles, equilibria of the frame
  rotating with the forcing; its Hopf curve (a pair of eigenvalues of the rotating frame's Jacobian with zero
  sum, by Orlando's formula the Hurwitz determinant ``a1 a2 a3 - a3^2 - a1^2 a4``), its fold curve (the double
  root of the whirl's quadratic) and its Bogdanov-Takens point (the fold where ``a3`` vanishes too);
* ``kappa`` along the curve: the library's ``(mu_1 + mu_2) / 2`` of the pair with product 1 against ``cosh(lambda
  T)`` of the closed-form pair ``+-lambda``.

Run ``python docs/hooks/gallery_rotor.py OUT.png`` to compute the figure by hand.
"""

from __future__ import annotations

#: The rotor of the page (``delta = 1``, no gravity) and the start of its branch.
ROTOR = {"zeta": 0.2, "beta": 3.0, "delta": 1.0, "rho": 0.3}
MU0, OMEGA0 = -0.35, 1.25
#: The whirl at (OMEGA0, MU0), rounded: the shooting converges from it.
X0 = (1.0857, -0.8548, 1.0685, 1.3572)
MU_RANGE = (-0.43, -0.33)

_R = "sqrt(x**2 + y**2)"


def rotor(mu: float = MU0, omega: float = OMEGA0):
    """The Jeffcott rotor with a snubber ring, its modes written out (``free``, ``contact``; surface ``gap``)."""
    from saltation import Crossing, Mode, PiecewiseSystem, Transition

    fx, fy = "rho*omega**2*cos(omega*t)", "rho*omega**2*sin(omega*t)"
    return PiecewiseSystem(
        name="jeffcott_snubber",
        states=["x", "y", "vx", "vy"],
        parameters=dict(ROTOR, mu=mu, omega=omega),
        modes=[Mode("contact", ["vx", "vy", f"-2*zeta*vx - x - beta*(1 - delta/{_R})*(x - mu*y) + {fx}",
                                f"-2*zeta*vy - y - beta*(1 - delta/{_R})*(mu*x + y) + {fy}"],
                    domain=[f"{_R} - delta > 0"]),
               Mode("free", ["vx", "vy", f"-2*zeta*vx - x + {fx}", f"-2*zeta*vy - y + {fy}"])],
        surfaces={"gap": f"{_R} - delta"},
        transitions=[Transition("free", "gap", Crossing.RISING, "contact"),
                     Transition("contact", "gap", Crossing.FALLING, "free")],
        period="2*pi/omega",
    )


# ---------------------------------------------------------------------------------------------------------------
# closed forms of the rotating frame (numpy and scipy only)
# ---------------------------------------------------------------------------------------------------------------


def _quadratic(omega: float, mu: float):
    """``|a R - b| = rho omega^2`` as ``c2 R^2 + c1 R + c0 = 0``, with ``a`` and ``b``."""
    zeta, beta, delta, rho = (ROTOR[k] for k in ("zeta", "beta", "delta", "rho"))
    a = 1 - omega**2 + beta + 1j * (2 * zeta * omega + beta * mu)
    b = beta * delta * (1 + 1j * mu)
    return abs(a) ** 2, -2 * (a * b.conjugate()).real, abs(b) ** 2 - rho**2 * omega**4, a, b


def discriminant(omega: float, mu: float) -> float:
    """The discriminant of the whirl's quadratic in ``R``, divided by ``c2``: zero on the fold curve."""
    c2, c1, c0, _, _ = _quadratic(omega, mu)
    return (c1 * c1 - 4 * c2 * c0) / c2


def whirl(omega: float, mu: float, root: int = 1):
    """``w* = R exp(-i phi)`` of the larger root ``R`` (``root = 1``), the smaller one (``-1``) or the double root
    (``0``, its discriminant taken as zero), or None where there is none beyond the clearance."""
    import numpy as np

    c2, c1, c0, a, b = _quadratic(omega, mu)
    disc = c1 * c1 - 4 * c2 * c0
    if disc < 0 and root:
        return None
    R = (-c1 + root * np.sqrt(max(disc, 0.0))) / (2 * c2)
    if R <= ROTOR["delta"]:
        return None
    return ROTOR["rho"] * omega**2 / (a - b / R)


def rotating_jacobian(omega: float, mu: float, w: complex):
    """The Jacobian of ``w'' + 2 (zeta + i omega) w' + (1 - omega^2 + 2 i zeta omega) w + beta (1 - delta/|w|)
    (1 + i mu) w = rho omega^2`` at the whirl ``w``, for the state ``(Re w, Im w, Re w', Im w')``."""
    import numpy as np

    zeta, beta, delta = ROTOR["zeta"], ROTOR["beta"], ROTOR["delta"]
    R = abs(w)
    u = np.array([w.real, w.imag])
    D = (1 - delta / R) * np.eye(2) + delta * np.outer(u, u) / R**3
    K = np.array([[1.0, -mu], [mu, 1.0]])
    J2 = np.array([[0.0, -1.0], [1.0, 0.0]])
    jac = np.zeros((4, 4))
    jac[:2, 2:] = np.eye(2)
    jac[2:, :2] = -(1 - omega**2) * np.eye(2) - 2 * zeta * omega * J2 - beta * K @ D
    jac[2:, 2:] = -2 * zeta * np.eye(2) - 2 * omega * J2
    return jac


def hurwitz(omega: float, mu: float, root: int = 1) -> float:
    """``a1 a2 a3 - a3^2 - a1^2 a4`` of ``det(lambda I - J) = lambda^4 + a1 lambda^3 + ... + a4`` at a whirl
    (:func:`whirl`'s ``root``): the product of the sums of the eigenvalues two by two (Orlando's formula), zero
    where a pair has zero sum."""
    import numpy as np

    _, a1, a2, a3, a4 = np.poly(rotating_jacobian(omega, mu, whirl(omega, mu, root)))
    return a1 * a2 * a3 - a3 * a3 - a1 * a1 * a4


def fold_omega(mu: float) -> float:
    """The rotating frame's fold at ``mu``: the double root of the quadratic, by brentq in ``omega``."""
    from scipy.optimize import brentq

    return brentq(lambda om: discriminant(om, mu), 1.0, 1.25, xtol=1e-15, rtol=1e-15)


def bogdanov_takens() -> tuple[float, float]:
    """``(omega, mu)`` on the fold curve where ``a3`` (the coefficient of ``lambda``) vanishes too: a double zero
    eigenvalue of ``J``."""
    import numpy as np
    from scipy.optimize import brentq

    def a3(mu):
        om = fold_omega(mu)
        return np.poly(rotating_jacobian(om, mu, whirl(om, mu, 0)))[3]

    mu = brentq(a3, -0.43, -0.41, xtol=1e-15, rtol=1e-15)
    return fold_omega(mu), mu


def hopf_curve(mus):
    """The closed-form Hopf (and neutral-saddle) curve: at each ``mu`` the ``omega`` beyond the fold where the
    Hurwitz determinant of the upper or of the lower whirl vanishes, by brentq after a scan; with ``kappa =
    cosh(lambda T)`` of the zero-sum pair and whether that pair is imaginary (a Hopf point: a Neimark-Sacker point
    of the orbit).  Rows ``(omega, mu, kappa, imaginary)``."""
    import numpy as np
    from scipy.optimize import brentq

    def first_root(mu):
        grid = np.linspace(fold_omega(mu) + 1e-9, 1.6, 400)
        for root in (1, -1):
            values = [hurwitz(om, mu, root) if whirl(om, mu, root) is not None else np.nan for om in grid]
            for i in range(len(grid) - 1):
                if values[i] * values[i + 1] < 0:
                    return brentq(hurwitz, grid[i], grid[i + 1], args=(mu, root), xtol=1e-14), root
        return None, None

    out = []
    for mu in mus:
        om, root = first_root(mu)
        if om is None:
            continue
        lam = np.linalg.eigvals(rotating_jacobian(om, mu, whirl(om, mu, root)))
        i, _ = min(((i, j) for i in range(4) for j in range(i + 1, 4)), key=lambda ij: abs(lam[ij[0]] + lam[ij[1]]))
        out.append((om, mu, np.cosh(lam[i] * 2 * np.pi / om).real, abs(lam[i].imag) > abs(lam[i].real)))
    return np.array(out)


def _kappa(multipliers) -> float:
    """``(mu_1 + mu_2) / 2`` of the pair of multipliers whose product is nearest 1."""
    import itertools

    pair = min(itertools.combinations(multipliers, 2), key=lambda m: abs(m[0] * m[1] - 1))
    return float((pair[0] + pair[1]).real / 2)


def figure_neimark_sacker():
    """The Neimark-Sacker and fold curves in (omega, mu) over their closed forms, the 1:1 resonance; kappa."""
    import numpy as np
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from saltation import ContinuationSettings, continue_orbit, find_periodic_orbit
    from saltation.special_points.loci import follow_locus

    whirl = find_periodic_orbit(rotor(), list(X0))
    up = continue_orbit(whirl, "omega", bounds=(OMEGA0, 1.45), directions=(1,),
                        settings=ContinuationSettings(ds=0.02, ds_max=0.05))
    (ns,) = [sp for sp in up.special_points if sp.kind.value == "neimark_sacker"]
    curve = follow_locus(up, ns, "mu", MU_RANGE, settings=ContinuationSettings(ds=0.005, ds_max=0.01))
    down = continue_orbit(whirl, "omega", bounds=(1.0, OMEGA0), directions=(-1,),
                          settings=ContinuationSettings(ds=0.02, ds_max=0.05))
    (fold,) = [sp for sp in down.special_points if sp.kind.value == "fold"]
    fold_curve = follow_locus(down, fold, "mu", MU_RANGE, settings=ContinuationSettings(ds=0.005, ds_max=0.01))

    bt = bogdanov_takens()
    mus = np.concatenate([np.linspace(MU_RANGE[0], bt[1], 30, endpoint=False),
                          np.linspace(bt[1], MU_RANGE[1], 80)[1:]])
    hopf = hopf_curve(mus)
    fold_ref = np.array([fold_omega(mu) for mu in mus])
    at_bt = np.array([[bt[0], bt[1], 1.0, 1.0]])
    on_circle = np.array([bp.curve_kind is not None for bp in curve.points])
    values = curve.values

    fig = Figure(figsize=(10.0, 6.6), layout="constrained")
    axes = fig.subplot_mosaic([["plane", "zoom"], ["plane", "kappa"]], width_ratios=[1.25, 1])
    ax1, zoom, ax2 = axes["plane"], axes["zoom"], axes["kappa"]
    for ax in (ax1, zoom):
        for is_ns, color in ((True, "C0"), (False, "0.6")):  # the two parts meet at the Bogdanov-Takens point
            part = np.vstack([hopf[hopf[:, 3].astype(bool) == is_ns], at_bt])
            part = part[np.argsort(part[:, 1])]
            ax.plot(part[:, 0], part[:, 1], color=color, linewidth=5, alpha=0.35,
                    label="closed form: Hopf curve of the rotating frame" if is_ns else
                    "closed form: a real pair $\\pm\\lambda$ (neutral saddle)")
        ax.plot(fold_ref, mus, color="C1", linewidth=5, alpha=0.35, label="closed form: fold (double root $R$)")
        ax.plot(values[on_circle, 0], values[on_circle, 1], "k.", markersize=3, label="follow_locus: Neimark-Sacker")
        ax.plot(values[~on_circle, 0], values[~on_circle, 1], ".", color="0.45", markersize=3,
                label="follow_locus: neutral saddle")
        ax.plot(fold_curve.values[:, 0], fold_curve.values[:, 1], "x", color="C1", markersize=4,
                label="follow_locus: fold")
        ax.plot([bt[0]], [bt[1]], "*", color="C3", markersize=16, alpha=0.5, label="closed form: Bogdanov-Takens")
        for sp in curve.special_points + fold_curve.special_points:
            ax.plot([sp.parameter], [sp.second_parameter], "o", markerfacecolor="none", markeredgecolor="k",
                    markersize=9)
    ax1.plot([ns.parameter], [MU0], "s", markerfacecolor="white", markeredgecolor="k", markersize=7,
             label=f"Neimark-Sacker point of the branch at $\\mu = {MU0}$")
    ax1.plot([], [], "o", markerfacecolor="none", markeredgecolor="k", markersize=9,
             label="strong_resonance_1_1 (both curves)")
    zoom.set_xlim(bt[0] - 0.003, bt[0] + 0.005)
    zoom.set_ylim(MU_RANGE[0], bt[1] + 0.008)
    zoom.set_xlabel("omega")
    zoom.set_ylabel("mu")
    zoom.set_title("near the 1:1 resonance")
    ax1.add_patch(Rectangle((bt[0] - 0.003, MU_RANGE[0]), 0.008, bt[1] + 0.008 - MU_RANGE[0], fill=False,
                            edgecolor="0.5", linewidth=0.8))
    ax1.set_xlabel("omega")
    ax1.set_ylabel("mu (contact friction)")
    ax1.set_title("Neimark-Sacker and fold curves in (omega, mu)")
    ax1.legend(fontsize="x-small", loc="lower right")

    kappa = np.array([_kappa(bp.multipliers) for bp in curve.points])
    hopf = np.vstack([hopf, at_bt])
    hopf = hopf[np.argsort(hopf[:, 1])]
    ax2.plot(hopf[:, 1], hopf[:, 2], color="C0", linewidth=5, alpha=0.35,
             label="closed form: $\\cosh(\\lambda T)$, $\\lambda$ the zero-sum pair")
    ax2.plot(values[on_circle, 1], kappa[on_circle], "k.", markersize=3,
             label="library: $(\\mu_1 + \\mu_2)/2$ on the curve")
    ax2.plot(values[~on_circle, 1], kappa[~on_circle], ".", color="0.45", markersize=3)
    ax2.axhline(1.0, color="0.6", linewidth=0.8, linestyle=":")
    for sp in curve.special_points:
        ax2.plot([sp.second_parameter], [1.0], "o", markerfacecolor="none", markeredgecolor="k", markersize=9)
        ax2.annotate("1:1 resonance", (sp.second_parameter, 1.0), xytext=(10, 6), textcoords="offset points",
                     fontsize="small")
    ax2.set_xlabel("mu")
    ax2.set_ylabel("kappa = cos theta")
    ax2.set_title("kappa along the curve (> 1: a neutral saddle)")
    ax2.legend(fontsize="x-small", loc="upper right")

    records = [{"kind": "neimark_sacker", "parameter": "omega", "value": float(ns.parameter),
                "accuracy": float(ns.accuracy)}]
    records += [{"kind": f"{sp.codimension_two.value} ({' -> '.join(sp.sides)})",
                 "parameter": f"omega (at mu = {sp.second_parameter:.8f})",
                 "value": float(sp.parameter), "accuracy": float(sp.accuracy)}
                for sp in curve.special_points + fold_curve.special_points]
    return fig, records


if __name__ == "__main__":
    import json
    import sys
    import time
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))
    start = time.perf_counter()
    figure, found = figure_neimark_sacker()
    figure.savefig(sys.argv[1] if len(sys.argv) > 1 else "neimark_sacker.png", dpi=110)
    print(json.dumps({"points": found, "seconds": time.perf_counter() - start}, indent=1))
