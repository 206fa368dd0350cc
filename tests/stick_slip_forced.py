"""A forced oscillator on a moving belt, static friction F_s above kinetic F_k, the stick phase a mode."""
from saltation import Crossing, Mode, PiecewiseSystem, Transition

R, F = Crossing.RISING, Crossing.FALLING
FORCE = "-x - 2*zeta*v_b + a*cos(omega*t)"   # spring, damper and forcing on a block moving with the belt


def stick_slip(**overrides):
    return PiecewiseSystem(
        name="stick_slip_forced",
        states=["x", "v"],
        parameters={"zeta": 0.05, "F_k": 0.3, "F_s": 0.5, "a": 1.0, "omega": 0.8, "v_b": 0.5} | overrides,
        modes=[
            Mode("slip_plus", ["v", "-2*zeta*v - x - F_k + a*cos(omega*t)"], domain=["v - v_b > 0"]),
            Mode("slip_minus", ["v", "-2*zeta*v - x + F_k + a*cos(omega*t)"], domain=["v - v_b < 0"]),
            Mode("stick", ["v_b", "0"]),
        ],
        surfaces={"v_rel": "v - v_b", "up": f"{FORCE} - F_s", "down": f"{FORCE} + F_s"},
        transitions=[
            Transition("slip_minus", "v_rel", R, "stick", guard=[f"{FORCE} - F_s < 0"]),
            Transition("slip_minus", "v_rel", R, "slip_plus", guard=[f"{FORCE} - F_s >= 0"]),
            Transition("slip_plus", "v_rel", F, "stick", guard=[f"{FORCE} + F_s > 0"]),
            Transition("slip_plus", "v_rel", F, "slip_minus", guard=[f"{FORCE} + F_s <= 0"]),
            Transition("stick", "up", R, "slip_plus"),
            Transition("stick", "down", F, "slip_minus"),
        ],
        period="2*pi/omega",
    )


# --- an independent reference (numpy and scipy only) -------------------------------------------------------------

def reference_flow(state, t0: float, t1: float, **overrides):
    """The same oscillator integrated with ``solve_ivp`` (DOP853, rtol 1e-12) and its own stick-slip logic: slip
    until the relative velocity vanishes, then stick (moving with the belt) while the spring, damper and forcing
    stay within the static friction ``F_s``, or slip on the other side."""
    import numpy as np
    from scipy.integrate import solve_ivp

    q = {"zeta": 0.05, "F_k": 0.3, "F_s": 0.5, "a": 1.0, "omega": 0.8, "v_b": 0.5} | overrides
    zeta, Fk, Fs, a, w, vb = (q[k] for k in ("zeta", "F_k", "F_s", "a", "omega", "v_b"))

    def force(t, x):
        return -x - 2 * zeta * vb + a * np.cos(w * t)

    def slip(sign):
        return lambda t, y: [y[1], -2 * zeta * y[1] - y[0] - sign * Fk + a * np.cos(w * t)]

    y, t = np.array(state, dtype=float), float(t0)
    mode = "plus" if y[1] > vb else ("minus" if y[1] < vb else "stick")
    opts = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-13}
    while t < t1:
        if mode == "stick":
            up = lambda s, z: force(s, z[0]) - Fs  # noqa: E731
            down = lambda s, z: force(s, z[0]) + Fs  # noqa: E731
            up.terminal = down.terminal = True
            up.direction, down.direction = 1, -1
            sol = solve_ivp(lambda s, z: [vb, 0.0], (t, t1), y, events=(up, down), **opts)
            y, t = sol.y[:, -1].copy(), sol.t[-1]
            if sol.status == 1:
                mode = "plus" if sol.t_events[0].size else "minus"
            continue
        sign = 1.0 if mode == "plus" else -1.0
        rel = lambda s, z: z[1] - vb  # noqa: E731
        rel.terminal, rel.direction = True, -sign
        sol = solve_ivp(slip(sign), (t, t1), y, events=rel, **opts)
        y, t = sol.y[:, -1].copy(), sol.t[-1]
        if sol.status == 1:
            y[1] = vb
            f = force(t, y[0])
            mode = "stick" if abs(f) < Fs else ("plus" if f > 0 else "minus")
    return y
