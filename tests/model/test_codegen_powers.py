"""Integer powers in generated model code are printed as products, and compute what ``**`` does."""

from __future__ import annotations

import math

import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from saltation.engine.codegen import _Printer

X, Y = sp.symbols("x y")
PRINTER = _Printer({X: "x[0]", Y: "x[1]"})


@settings(max_examples=100, deadline=None)
@given(st.integers(-8, 8).filter(lambda e: abs(e) >= 2), st.floats(-50, 50).filter(lambda v: abs(v) > 1e-3),
       st.floats(-50, 50))
def test_small_integer_powers_are_products_equal_to_pow(exponent, x, y):
    """``b**e`` for 2 <= |e| <= 8 is printed without ``**`` (no libm ``pow`` call in the compiled field), and
    its value is Python's ``pow`` of the same base to a few rounding units (one per product)."""
    expr = (X + Y) ** exponent if abs(x + y) > 1e-3 else X ** exponent
    code = PRINTER.doprint(expr)
    assert "**" not in code
    value = eval(code, {"math": math, "x": [x, y]})
    base = x + y if abs(x + y) > 1e-3 else x
    reference = math.pow(base, exponent)
    assert abs(value - reference) <= 2 * abs(exponent) * 2.3e-16 * abs(reference)


def test_other_powers_keep_the_power_operator():
    assert PRINTER.doprint(X**2.5) == "x[0]**2.5"
    assert PRINTER.doprint(X**9) == "x[0]**9.0"
    assert PRINTER.doprint(sp.sqrt(X)) == "math.sqrt(x[0])"
