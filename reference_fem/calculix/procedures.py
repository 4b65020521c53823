"""The ccx procedure a deck runs (the solver option ``procedure``): what each takes, its element
and its step cards.

* ``implicit``: ``*DYNAMIC`` (Newmark's average acceleration) on the serendipity elements, at
  the case's dt where linear. ccx 2.20 runs it as a nonlinear step with at least two iterations
  per increment: two factorizations an increment, even for a linear model.
* ``explicit``: ``*DYNAMIC, EXPLICIT``: central differences on a lumped mass, the increment
  ccx's own from the Courant limit, on linear elements (the quadratic mesh split 2 x 2 (x 2),
  :mod:`.linear`), as ccx's manual advises for explicit work. ccx writes at every increment
  (2.20 ignores ``TIME POINTS`` there), so the deck writes every N increments, at least four
  times a dt (:mod:`.courant`); the probes are interpolated onto the dt grid.
* ``modal``: ``*FREQUENCY, STORAGE=YES`` with ``modes`` modes, then ``*MODAL DYNAMIC`` at the
  case's dt: each mode integrated exactly under piecewise-linear amplitudes; linear only, its
  error the truncation in the number of modes.
"""

from __future__ import annotations

from cases.params import UnsupportedCase

from ..frames import AXISYMMETRIC, SOLID

IMPLICIT, EXPLICIT, MODAL = "implicit", "explicit", "modal"
PROCEDURES = (IMPLICIT, EXPLICIT, MODAL)
#: the modal procedure's modes when none are given
MODES = 100
#: smallest increment ccx may cut back to, as a fraction of dt (plastic runs)
MIN_INCREMENT = 1e-4
#: increments an explicit step may take (ccx stops at INC; the Courant increment decides how many)
EXPLICIT_INCREMENTS = 10**7


def refuse(case, procedure: str, modes: int | None) -> None:
    """What ``procedure`` cannot take, in one line (:class:`UnsupportedCase`), before any work."""
    if procedure not in PROCEDURES:
        raise UnsupportedCase(f"calculix: procedure={procedure!r} is not one of {', '.join(PROCEDURES)}")
    if modes is not None and procedure != MODAL:
        raise UnsupportedCase(f"calculix: modes={modes} is the modal procedure's option, not {procedure}'s")
    if procedure == MODAL and case.material.plastic:
        raise UnsupportedCase("calculix (modal): a modal superposition is linear: it takes no plasticity "
                              "(procedure=implicit or explicit do)")
    if procedure == MODAL and (case.wall is not None or case.contacts):
        raise UnsupportedCase("calculix (modal): a modal superposition is linear: it takes no contact")
    if procedure == EXPLICIT and (case.wall is not None or case.contacts):
        raise UnsupportedCase("calculix (explicit): contact is not exported to ccx's explicit dynamics (its "
                              "node-to-face contact is not checked against the reference here)")
    if procedure == EXPLICIT and case.axisymmetric:
        raise UnsupportedCase("calculix (explicit): ccx 2.20 expands an axisymmetric element into a 2-degree wedge "
                              "whose width vanishes at the axis, so its Courant increment is about dt / 350 (the dome "
                              "at refine 1: 322 CPU s, 30 % off the reference on its mesh)")
    if procedure == EXPLICIT and case.initial_velocity:
        raise UnsupportedCase("calculix (explicit): an initial velocity is not exported to ccx's explicit dynamics "
                              "(2D models carry it on massless point masses, which a lumped mass cannot take)")


def check_modes(modes: int, free: int) -> None:
    """Refuse more modes than the model's ``free`` dofs (ccx's eigensolver needs fewer)."""
    if modes >= free:
        raise UnsupportedCase(f"calculix (modal): modes={modes} is out of range: the mesh has {free} free dofs; "
                              "take fewer modes or a finer mesh")


def linear(procedure: str) -> bool:
    """The procedure runs on linear elements (the quadratic mesh split, :mod:`.linear`)."""
    return procedure == EXPLICIT


def element(rep: str, procedure: str, plastic: bool = False) -> str:
    """ccx's element for a representation (plane strain, axisymmetric, solid) and a procedure.

    The explicit procedure's linear elements are fully integrated on elastic bodies and reduced
    (one point, ccx's hourglass control) on plastic ones, as an explicit user picks them: in
    plastic flow, which keeps the volume, the fully integrated ones lock (the notched strip at
    refine 1, 2: mid_uz 1.76, 2.54 % from the truth with CPE4, 0.69 % at refine 1 with CPE4R;
    the notched cylinder at refine 1: 8.9 % with C3D8, 5.3 % with C3D8R), while on elastic
    bodies the reduced ones are dearer and less accurate (the thick cylinder at refine 1: B_ut
    3.19 % in 42 CPU s with CPE4, 4.12 % in 63 s with CPE4R; the layered cylinder 3.67 against
    6.10 %)."""
    if linear(procedure):
        full = "C3D8" if rep == SOLID else ("CAX4" if rep == AXISYMMETRIC else "CPE4")
        return full + "R" if plastic else full
    return "C3D20" if rep == SOLID else ("CAX8" if rep == AXISYMMETRIC else "CPE8")


def fixed_increments(case, procedure: str = IMPLICIT) -> bool:
    """Implicit linear runs march at the case's dt exactly. With plasticity ccx's Newton can fail
    at dt in the first steps of a shock load (the thick cylinder at nu = 0, in its first
    increment): there ccx chooses its increments, at most dt, and the results are interpolated
    onto dt. The explicit procedure's increment is always ccx's; the modal one's is dt."""
    return procedure == MODAL or (procedure == IMPLICIT and not case.material.plastic)


def step_cards(case, procedure: str, modes: int | None) -> list[str]:
    """The step's opening cards (one step; the modal procedure's frequency step before it)."""
    dt, t_end = f"{case.dt:.13g}", f"{case.t_end:.13g}"
    if procedure == MODAL:
        return ["*STEP", "*FREQUENCY, STORAGE=YES", f"{modes or MODES}", "*END STEP",
                f"*STEP, INC={case.n_steps + 10}", "*MODAL DYNAMIC", f"{dt}, {t_end}"]
    if procedure == EXPLICIT:
        # the fourth value, the largest increment: without it ccx 2.20 selects a zero increment
        return [f"*STEP, INC={EXPLICIT_INCREMENTS}", "*DYNAMIC, EXPLICIT", f"{dt}, {t_end}, , {dt}"]
    if fixed_increments(case):
        return [f"*STEP, INC={case.n_steps + 10}", "*DYNAMIC, DIRECT, ALPHA=0.", f"{dt}, {t_end}"]
    # ccx's own increments, at most dt, cut back where its Newton does not converge
    return [f"*STEP, INC={100 * case.n_steps}", "*DYNAMIC, ALPHA=0.",
            f"{dt}, {t_end}, {case.dt * MIN_INCREMENT:.13g}, {dt}"]
