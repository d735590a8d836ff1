"""The contact laws' registry: each normal and tangential law's name (what a scenario
writes in contact.normal_law, [[contact.pairs]].normal_law and contact.tangential_law)
and its law id, the integer value a contact's coefficient row holds in its law column
(physics.contact's COEF_NLAW, COEF_TLAW), on which physics.laws and the tangential
passes dispatch. Setup lists the allowed names from here (setup.scenario's NORMAL_LAWS,
TANGENTIAL_LAWS), model.coefficients writes the ids into the rows: a new law is its
module, one line here and its branch in the dispatch (docs/architecture.md, "Adding a
normal law").

Pure data (no numba): the ids are read as compile-time constants by the kernels.
"""

from __future__ import annotations

#: Normal laws, name -> law id (COEF_NLAW): "hertz", eq. (2) with eq. (3)'s damping
#: (physics.contact); "thornton", Thornton's elastic-perfectly plastic law (docs/model.md
#: section 3.6, physics.plastic); "johnson", Hertz to yield, then Johnson's expanding cavity
#: up to the hardness with a rate-dependent yield strength (section 3.10, physics.cavity).
NORMAL_LAW_IDS: dict[str, int] = {"hertz": 0, "thornton": 1, "johnson": 2}
HERTZ, THORNTON, JOHNSON = NORMAL_LAW_IDS["hertz"], NORMAL_LAW_IDS["thornton"], NORMAL_LAW_IDS["johnson"]
#: Normal laws that yield at the overlap COEF_DY: they need the yield strength Y of every
#: body that can yield at the contact, and take Hertz's code while the contact's overlap and
#: largest overlap stay at or below COEF_DY.
YIELDING_LAWS: tuple[str, ...] = ("thornton", "johnson")

#: Tangential laws, name -> law id (COEF_TLAW): "tanh", eq. (5)'s regularised Coulomb law
#: without history (physics.contact); "mindlin", Mindlin's tangential spring with a Coulomb
#: limit and the contact's tangential displacement as history (docs/model.md section 3.16,
#: physics.mindlin).
TANGENTIAL_LAW_IDS: dict[str, int] = {"tanh": 0, "mindlin": 1}
TANH, MINDLIN = TANGENTIAL_LAW_IDS["tanh"], TANGENTIAL_LAW_IDS["mindlin"]
