"""The contact laws' registry: each normal and tangential law's name (what a scenario
writes in contact.normal_law, [[contact.pairs]].normal_law and contact.tangential_law)
and its law id, the integer value a contact's coefficient row holds in its law column
(physics.contact's COEF_NLAW, COEF_TLAW), on which physics.laws and the tangential
passes dispatch. Setup lists the allowed names from here (setup.scenario's NORMAL_LAWS,
TANGENTIAL_LAWS), model.coefficients writes the ids into the rows.

A normal law is one module and one line of NORMAL_LAW_REGISTRY: the module gives the
law's compiled functions (`law_response`, `law_force`, `law_slopes`, `law_rate`) and its
coefficient columns (`law_columns`), and physics.laws builds the dispatch on the law id
from this table (docs/architecture.md, "Adding a normal law"). A tangential law likewise is
one module and one line of TANGENTIAL_LAW_REGISTRY ("Adding a tangential law").

Pure data (no numba): the ids are read as compile-time constants by the kernels.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class NormalLaw:
    """One normal law: `module`, the module that implements it (its `law_*` functions);
    `yields`, whether it yields at the overlap COEF_DY (then it needs the yield strength Y
    of every body that can yield at the contact, and setup refuses it where Y is unknown)."""

    module: str
    yields: bool = False


#: Normal laws, name -> implementation, in the order of their law ids (COEF_NLAW):
#: "hertz", eq. (2) with eq. (3)'s damping (physics.hertz); "thornton", Thornton's
#: elastic-perfectly plastic law (docs/model.md section 3.6, physics.plastic); "johnson",
#: Hertz to yield, then Johnson's expanding cavity up to the hardness with a rate-dependent
#: yield strength (section 3.10, physics.cavity).
NORMAL_LAW_REGISTRY: dict[str, NormalLaw] = {
    "hertz": NormalLaw("granplate.physics.hertz"),
    "thornton": NormalLaw("granplate.physics.plastic", yields=True),
    "johnson": NormalLaw("granplate.physics.cavity", yields=True),
}
#: name -> law id, the position in NORMAL_LAW_REGISTRY (Hertz's id 0: an elastic contact
#: takes its branch after one compare)
NORMAL_LAW_IDS: dict[str, int] = {name: k for k, name in enumerate(NORMAL_LAW_REGISTRY)}
HERTZ, THORNTON, JOHNSON = NORMAL_LAW_IDS["hertz"], NORMAL_LAW_IDS["thornton"], NORMAL_LAW_IDS["johnson"]
#: Normal laws that yield at the overlap COEF_DY (NormalLaw.yields).
YIELDING_LAWS: tuple[str, ...] = tuple(name for name, law in NORMAL_LAW_REGISTRY.items() if law.yields)


@dataclass(frozen=True)
class TangentialLaw:
    """One tangential law: `module`, the module that implements it; `history`, whether it
    keeps a history per contact (a tangential displacement, as Mindlin's spring: its module
    gives `law_scale`, `law_stiffness`, `law_energy`, `law_step`, `law_stage`, and the
    history passes run it) or is a rate law (its force follows from |N| and the slip rate:
    `law_friction`, `law_slopes`, `law_relaxed_slip`, run by the rate passes and the split
    friction). Either gives `law_columns`."""

    module: str
    history: bool = False


#: Tangential laws, name -> implementation, in the order of their law ids (COEF_TLAW):
#: "tanh", eq. (5)'s regularised Coulomb law without history (physics.tanh_friction);
#: "mindlin", Mindlin's tangential spring with a Coulomb limit and the contact's tangential
#: displacement as history (docs/model.md section 3.16, physics.mindlin); "mindlin_force",
#: the same law in its incremental form, the elastic tangential force as history (LAMMPS's
#: `mindlin_rescale/force`, physics.mindlin_force).
TANGENTIAL_LAW_REGISTRY: dict[str, TangentialLaw] = {
    "tanh": TangentialLaw("granplate.physics.tanh_friction"),
    "mindlin": TangentialLaw("granplate.physics.mindlin", history=True),
    "mindlin_force": TangentialLaw("granplate.physics.mindlin_force", history=True),
}
#: name -> law id, the position in TANGENTIAL_LAW_REGISTRY
TANGENTIAL_LAW_IDS: dict[str, int] = {name: k for k, name in enumerate(TANGENTIAL_LAW_REGISTRY)}
TANH, MINDLIN = TANGENTIAL_LAW_IDS["tanh"], TANGENTIAL_LAW_IDS["mindlin"]
#: Tangential laws that keep a history per contact (TangentialLaw.history).
HISTORY_LAWS: tuple[str, ...] = tuple(name for name, law in TANGENTIAL_LAW_REGISTRY.items() if law.history)
