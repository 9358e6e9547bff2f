"""Status codes of the compiled solver and their messages.

Only :data:`PUBLIC_STATUS` codes reach a result: the internal :data:`BLOCKED` (steps refused by
the anti-tunnelling tests) makes the driver widen the candidate set and never leaves it.
"""

from __future__ import annotations

OK = 0
ITER_LIMIT = 1
LINALG_FAIL = 2
LINESEARCH_FAIL = 3
CONTACT_CYCLE = 4
POLISH_FAIL = 5
INFEASIBLE_START = 6
SADDLE = 7
INVERTED = 8
PENETRATION = 9
BLOCKED = 10  # internal: steps refused by an anti-tunnelling test; widen the candidate set
STATUS_MESSAGES = {
    OK: "converged",
    ITER_LIMIT: "interior-point iteration limit reached",
    LINALG_FAIL: "Newton matrix could not be made positive definite",
    LINESEARCH_FAIL: "line search failed to decrease the barrier merit",
    CONTACT_CYCLE: "contact candidate set did not settle (cycling between finger tip and face)",
    POLISH_FAIL: "active-set polish did not reach the contact tolerance",
    INFEASIBLE_START: "start point violates a contact constraint",
    SADDLE: "stuck at an unstable (saddle) equilibrium; escapes from it failed",
    PENETRATION: "answer penetrates a finger outside the contact constraints considered",
    INVERTED: "equilibrium with inverted (folded) fan triangles: the squeeze is beyond the "
              "point-spring model's valid range",
    BLOCKED: "steps kept refused by the anti-tunnelling tests and no new contact candidate "
             "explains why",
}
NOT_SOLVED = -1  # batch rows that were not solved (invalid at rest)
CHECK_FAILED = 11  # the solver claimed an equilibrium the independent check rejected
FEM_FAILED = 12  # evaluate_designs(fidelity="fem"): the finite-element grasp did not converge
NOT_FINITE = 13  # batch rows with a design value that is not a finite number (not solved)
STATUS_MESSAGES[NOT_SOLVED] = "not solved: the design is invalid at rest"
STATUS_MESSAGES[CHECK_FAILED] = "independent equilibrium check failed"
STATUS_MESSAGES[FEM_FAILED] = "the finite-element grasp did not converge"
STATUS_MESSAGES[NOT_FINITE] = ("not solved: a design value is not a finite number (NaN or "
                               "inf)")
PUBLIC_STATUS = tuple(sorted(set(STATUS_MESSAGES) - {BLOCKED}))
