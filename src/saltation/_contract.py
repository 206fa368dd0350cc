"""The contract between the compiled integrator and Python, defined once.

Every generated kernel module starts with this file's text (numba folds its
names into constants), and :mod:`saltation.integrate` imports it to read the
kernel's results: the status codes, the kinds of events, the outcomes of the
kernel's Newton iterations, and the layout of the two packed result arrays.
Keep it free of imports: it is copied verbatim.
"""

# Status codes of an integration (saltation.integrate.Status).
STATUS_OK = 0
STATUS_MAX_EVENTS = 1
STATUS_CHATTERING = 2
STATUS_STEP_TOO_SMALL = 3
STATUS_NON_FINITE = 4
STATUS_SLIDING_UNDEFINED = 5
STATUS_MAX_STEPS = 6
STATUS_TANGENTIAL = 7
STATUS_OUTSIDE_DOMAIN = 8

# Kinds of switching events (saltation.integrate.EventKind).
EVENT_TRANSITION = 0
EVENT_SLIDING_START = 1
EVENT_SLIDING_END = 2

# Outcomes of the kernel's Newton iterations (correct_periodic).
SHOOT_CONVERGED = 0
SHOOT_FAILED = 1  # an integration failed, the residual is not finite, or no step reduces it
SHOOT_MAX_ITER = 2
SHOOT_BAD_PERIOD = 3  # a period that is not positive (the caller's own iteration explains it)
SHOOT_SINGULAR = 4  # a Newton matrix with a zero (or not finite) pivot (the caller's own iteration explains it)

# The integer array of an integration's result: status, mode and surface of a failure, number of events,
# steps, rejected steps, final mode, sliding state (SLIDE_WIDTH entries), initial mode; then the event
# log's rows (kind, transition, surface, mode from, mode to).
INFO_STATUS = 0
INFO_FAILED_MODE = 1
INFO_FAILED_SURFACE = 2
INFO_EVENTS = 3
INFO_STEPS = 4
INFO_REJECTED = 5
INFO_FINAL_MODE = 6
INFO_SLIDE = 7
SLIDE_WIDTH = 5
INFO_INITIAL_MODE = 12
INFO_EVENT_LOG = 13
EVENT_LOG_INTS = 5


def result_offsets(n):
    """Offsets in the float array of an integration's result, for ``n`` states: ``(x, Phi, psi, x_min,
    x_max, f at the end, event log)``. The time at the end comes first; the event log's rows are
    ``(t, x-, x+, S)``; after them the recorded steps and their dense-output coefficients."""
    x = 1
    phi = x + n
    psi = phi + n * n
    x_min = psi + n
    x_max = x_min + n
    velocity = x_max + n
    events = velocity + n
    return x, phi, psi, x_min, x_max, velocity, events
