"""How plots write a model's names: mathtext for states and parameters (:func:`tex_name`)."""

from __future__ import annotations

_GREEK = {
    "alpha", "beta", "gamma", "delta", "epsilon", "varepsilon", "zeta", "eta", "theta", "vartheta", "iota", "kappa",
    "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "varphi", "chi", "psi", "omega",
    "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Upsilon", "Phi", "Psi", "Omega",
}


def tex_name(name: str) -> str:
    """A model's name as mathtext (without ``$``): Greek letters by name (``omega`` -> ``\\omega``), the
    part after the first underscore as a subscript (``v_dr`` -> ``v_{dr}``, ``omega_n`` ->
    ``\\omega_{n}``), primes kept (``x'``)."""
    primes = len(name) - len(name.rstrip("'"))
    core = name[: len(name) - primes] if primes else name
    head, _, sub = core.partition("_")
    head = f"\\{head}" if head in _GREEK else head
    if sub:
        sub = f"\\{sub}" if sub in _GREEK else sub.replace("_", r"\_")
        head = f"{head}_{{{sub}}}"
    return head + "'" * primes


__all__ = ["tex_name"]
