"""The rules of [contact]: damping, friction, torque arm, detection, the normal law and the
yield strengths a yielding law needs at every contact that can form.
"""

from __future__ import annotations

from collections import Counter
from typing import Any


from granplate.errors import ScenarioError
from granplate.setup.fields import material_exists, nonneg, positive, string_in

# YIELDING_LAWS: the normal laws that need the yield strength Y of every body that can yield
# at a contact (both granules; the granule alone against a wall or the plate)
from granplate.setup.law_registry import TANGENTIAL_LAW_REGISTRY
from granplate.setup.law_registry import YIELDING_LAWS as YIELDING_LAWS
from granplate.setup.scenario import NORMAL_LAWS, TANGENTIAL_LAWS, Scenario


#: Lever arms of the friction torque (Contact.torque_arm).
#: "lammps": Mindlin's law only (LAMMPS's pair granular: the slip rate at the arm R, the torque
#: at R - delta/2 between spheres and R at a wall).
TORQUE_ARMS: tuple[str, ...] = ("radius", "contact_point", "lammps")
DETECTIONS: tuple[str, ...] = ("dynamic", "fixed")
#: Largest Coulomb coefficient (real dry pairs stay below about 2, rubber on glass).
MU_MAX = 10.0
#: Largest tanh smoothing k_s [s/m]: a smoothing slip rate 1/k_s of at least 1 um/s (the
#: paper's is 1 mm/s); a sharper law is a step in the slip rate that no time step resolves.
KS_MAX = 1e6
#: Largest damping coefficient alpha_n of eq. (3): near 2 a contact is already critically
#: damped (restitution about 0); more only stiffens the time integration.
ALPHA_N_MAX = 10.0


def _damping(path: str, alpha_n: Any) -> None:
    """alpha_n in [0, ALPHA_N_MAX] (None: not given)."""
    if alpha_n is None:
        return
    nonneg(path, alpha_n)
    if alpha_n > ALPHA_N_MAX:
        raise ScenarioError(
            path,
            alpha_n,
            f"must be in [0, {ALPHA_N_MAX:g}] (eq. 3's damping "
            "coefficient; near 2 a contact is already critically damped)",
        )


def _friction(path: str, mu: Any, k_s: Any) -> None:
    """mu in [0, MU_MAX] and k_s in (0, KS_MAX] (either None: not given)."""
    if mu is not None:
        nonneg(f"{path}.mu", mu)
        if mu > MU_MAX:
            raise ScenarioError(
                f"{path}.mu",
                mu,
                f"must be in [0, {MU_MAX:g}] (a Coulomb coefficient; real dry pairs stay below about 2)",
            )
    if k_s is not None:
        positive(f"{path}.k_s", k_s)
        if k_s > KS_MAX:
            raise ScenarioError(
                f"{path}.k_s",
                k_s,
                f"must be in (0, {KS_MAX:g}] s/m (a smoothing "
                "slip rate 1/k_s of at least 1 um/s; sharper, friction is a step no "
                "time step resolves)",
            )


def _check_contact(s: Scenario) -> None:
    c = s.contact
    _friction("contact", c.mu, c.k_s)
    _damping("contact.alpha_n", c.alpha_n)
    nonneg("contact.neighbour_gap", c.neighbour_gap)
    if c.neighbour_gap > 1.0:
        raise ScenarioError(
            "contact.neighbour_gap",
            c.neighbour_gap,
            "must be at most 1 (a gap of at most the smaller radius, as contact.skin)",
        )
    string_in("contact.torque_arm", c.torque_arm, TORQUE_ARMS)
    string_in("contact.detection", c.detection, DETECTIONS)
    string_in("contact.normal_law", c.normal_law, NORMAL_LAWS)
    positive("contact.skin", c.skin)
    if c.skin > 1.0:
        raise ScenarioError("contact.skin", c.skin, "must be at most 1 (a fraction of R_i + R_j)")
    positive("contact.overlap_warn", c.overlap_warn)
    if not c.overlap_warn < 1.0:
        raise ScenarioError(
            "contact.overlap_warn", c.overlap_warn, "must be in (0, 1) (a fraction of the smaller radius)"
        )
    positive("contact.overlap_stop", c.overlap_stop)
    if not c.overlap_warn <= c.overlap_stop < 1.0:
        raise ScenarioError(
            "contact.overlap_stop", c.overlap_stop, f"must lie in [contact.overlap_warn = {c.overlap_warn:g}, 1)"
        )
    if not isinstance(c.clip_tensile, bool):
        raise ScenarioError("contact.clip_tensile", c.clip_tensile, "must be true or false")
    for i, pc in enumerate(c.pairs):
        p = f"contact.pairs[{i}]"
        mats = pc.materials
        if not isinstance(mats, tuple) or len(mats) != 2:
            raise ScenarioError(f"{p}.materials", mats, "must be two material names")
        for k, m in enumerate(mats):
            material_exists(f"{p}.materials[{k}]", m, s)
        _damping(f"{p}.alpha_n", pc.alpha_n)
        _friction(p, pc.mu, pc.k_s)
        if pc.normal_law is not None:
            string_in(f"{p}.normal_law", pc.normal_law, NORMAL_LAWS)
    _check_yield_strengths(s)
    _check_tangential_law(s)


def _check_tangential_law(s: Scenario) -> None:
    """contact.tangential_law is one of TANGENTIAL_LAWS; a law with history ("mindlin") with
    the Poisson ratio of every granule material and of the elastic solid's (their G*, eq.
    M1). It runs at every contact kind under every scheme (docs/model.md section 3.16)."""
    c = s.contact
    string_in("contact.tangential_law", c.tangential_law, TANGENTIAL_LAWS)
    nonneg("contact.tangential_damping", c.tangential_damping)
    if c.tangential_damping > ALPHA_N_MAX:
        raise ScenarioError(
            "contact.tangential_damping",
            c.tangential_damping,
            f"must be in [0, {ALPHA_N_MAX:g}] (a factor on eq. 3's normal damping coefficient)",
        )
    history = TANGENTIAL_LAW_REGISTRY[c.tangential_law].history  # the rules of a law with history (Mindlin's)
    if not history and c.tangential_damping != 0.0:
        raise ScenarioError(
            "contact.tangential_damping",
            c.tangential_damping,
            "is Mindlin's (contact.tangential_law = 'mindlin'): the tanh law has no tangential damping; set 0",
        )
    if not history:
        if c.torque_arm == "lammps":
            raise ScenarioError(
                "contact.torque_arm",
                c.torque_arm,
                "'lammps' is an arm of contact.tangential_law = 'mindlin' only: "
                "with the tanh law take 'radius' or 'contact_point'",
            )
        return
    if s.solver.scheme != "verlet" and c.torque_arm == "lammps":
        raise ScenarioError(
            "contact.torque_arm",
            c.torque_arm,
            f"'lammps' (LAMMPS's torque arms) runs under solver.scheme = 'verlet' only, not {s.solver.scheme!r}: "
            "take 'radius' or 'contact_point'",
        )
    solid = [s.plate.material] if s.plate is not None else []
    for m in dict.fromkeys([*(g.material for g in s.granules), *solid]):
        nu = s.material(m).nu
        if not isinstance(nu, (int, float)) or isinstance(nu, bool) or not -1.0 < nu <= 0.5:
            raise ScenarioError(
                f"materials.{m}.nu",
                nu,
                "must be a Poisson ratio in (-1, 0.5]: contact.tangential_law = 'mindlin' takes "
                "the shear modulus E / (2 (1 + nu)) from it",
            )


def possible_contacts(s: Scenario) -> list[tuple[str, str, str]]:
    """(kind, a, b) for every pair of materials that can touch in the resolved scenario `s`:
    "granule-granule" for two materials of its granules (a with itself when two granules
    share it), "granule-wall" for a granule's material a and a wall's material b,
    "granule-plate" for a and the plate's material b; materials in the order the granules
    and walls first name them."""
    count = Counter(g.material for g in s.granules)
    mats = list(count)
    found = []
    for i, a in enumerate(mats):
        if count[a] > 1:
            found.append(("granule-granule", a, a))
        found += [("granule-granule", a, b) for b in mats[i + 1 :]]
    found += [("granule-wall", a, b) for a in mats for b in dict.fromkeys(w.material for w in s.walls)]
    if s.plate is not None:
        found += [("granule-plate", a, s.plate.material) for a in mats]
    return found


def _check_yield_strengths(s: Scenario) -> None:
    """A yielding normal law (YIELDING_LAWS) at a contact that can occur has the yield
    strength of each body there that can yield: both granules' materials, or the granule's
    alone against a wall or the plate (rigid bodies to the law, which never yield)."""
    c = s.contact
    for kind, a, b in possible_contacts(s):
        law = c.law_for_pair(a, b)
        if law not in YIELDING_LAWS:
            continue
        for m in dict.fromkeys((a, b) if kind == "granule-granule" else (a,)):
            if s.material(m).Y is None:
                k = c.law_index(a, b)
                path = "contact.normal_law" if k is None else f"contact.pairs[{k}].normal_law"
                raise ScenarioError(
                    path,
                    law,
                    f"needs the yield strength of material '{m}' ({kind} contacts {a}-{b}): set materials.{m}.Y [Pa]",
                )
