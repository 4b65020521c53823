"""The study of a scene from a file (``smfem study my_scene.toml``): the verification the built-in
scenes get, for a body the plan does not know.

Its series span the scene's own settings as the built-in scenes' do (:mod:`smfem.studies.plan`):
SMFEM at the scene's mesh and twice it (full: four times; harmonics with the mesh, for a scene
that has more than one), each at the scene's step, half and a quarter of it (full: an eighth);
the quadratic element; the reference FEM that can run the scene (2D where it has a 2D form,
else 3D) and, beside a 2D one, the 3D reference at the scene's mesh; in the full study also the
3D reference's explicit engine and CalculiX's three procedures (:data:`FULL_MODES`). Its truth is made as a
built-in scene's would be were it new (:func:`smfem.studies.truth.plan_for`: modal where the
scene is linear and homogeneous along x3, else the explicit reference over three meshes, else
time-step halving). Every level runs, in the full study too: a series is carried along its
ladder only against a stored truth (:mod:`smfem.studies.ladder`), and a scene file's truth is
made by the study itself.

A scene is named in jobs by its file's absolute path, so that a worker process reads it
wherever it runs; the run cache keys a run by the file's text as well (:mod:`smfem.studies.cache`).
"""

from __future__ import annotations

from pathlib import Path

from cases import get_case

from .plan import (CALCULIX, CALCULIX_EXPLICIT, CALCULIX_MODAL, REF2D, REF3D, REF3D_EXPLICIT, SMFEM, SMFEM_QUAD9, CaseStudy,
                   Series, grid)
from .plan import select as select_builtin
from .truth import plan_for, reference_solver

#: the scene's mesh (and harmonics) times these: the quick study's and the full one's
QUICK_SCALES, FULL_SCALES = (1, 2), (1, 2, 4)
#: the scene's step over these
QUICK_DIVISORS, FULL_DIVISORS = (1, 2, 4), (1, 2, 4, 8)
#: CalculiX's modal procedure in a full study: the scene's mesh with these many modes (its
#: truncation measured as the built-in scenes' is, :data:`smfem.studies.plan.CCX_MODAL`)
FULL_MODES = (50, 100, 200)


def is_scene_file(name) -> bool:
    """Whether ``name`` names a scene file (``*.toml``) rather than a built-in scene."""
    return str(name).lower().endswith(".toml")


def scene_ref(name: str) -> str:
    """How jobs name a scene: a file by its absolute path, a built-in scene by its name."""
    return str(Path(name).resolve()) if is_scene_file(name) else name


def study_of(name: str, full: bool = False, base: dict | None = None) -> CaseStudy:
    """The study of scene file ``name`` (quick, or ``full``), every run with the ``base``
    overrides (a shorter window, say)."""
    ref, base = scene_ref(name), dict(base or {})
    case = get_case(ref, base)
    scales, divisors = (FULL_SCALES, FULL_DIVISORS) if full else (QUICK_SCALES, QUICK_DIVISORS)
    refine = case.params.get("refine", 1)

    def spaces(k_values, harmonics: bool):
        """The scene's mesh (with SMFEM, its harmonics too, beyond one) times each of ``k_values``."""
        return tuple({"refine": k * refine, **({"harmonics": k * case.harmonics} if harmonics and case.harmonics > 1
                                               else {})} for k in k_values)

    def at(k_values, steps=divisors, harmonics=False):
        return grid(ref, spaces(k_values, harmonics), steps)

    reference = reference_solver(case)
    series = [Series(SMFEM, at(scales, harmonics=True)),
              Series(SMFEM_QUAD9, at(scales[:-1] if full else scales[:1], harmonics=True))]
    if reference == REF2D:
        meshes = scales
        series += [Series(REF2D, at(meshes)), Series(REF3D, at(scales[:1], (0.5, 1, 2) if full else (1,)))]
    else:  # 3D only: the reference at the scene's mesh, and at twice it in full
        meshes = scales[:2] if full else scales[:1]
        series += [Series(REF3D, at(meshes, (1, 2) if full else (1,)))]
    if full:
        # every competitor at its fastest, as on the built-in scenes: the 3D reference's explicit
        # engine (its own Courant step) at the 3D meshes, CalculiX's three procedures at the scene's
        # mesh; a procedure the scene cannot take is one run, refused in one line the report keeps
        series += [Series(REF3D_EXPLICIT, spaces(scales[:2], False)), Series(CALCULIX, ({},)),
                   Series(CALCULIX_EXPLICIT, ({},)), Series(CALCULIX_MODAL, tuple({"modes": m} for m in FULL_MODES))]
    # the same-dt reference: the finest reference mesh of the series; error estimates of SMFEM
    # and of a 2D reference (a 3D run's companions are 3D runs too, dear)
    return CaseStudy(ref, tuple(series), reference=(reference, spaces(meshes[-1:], False)[0]),
                     truth=plan_for(ref, base, "full" if full else "quick"), base=base,
                     estimated=(SMFEM, REF2D) if reference == REF2D else (SMFEM,))


def select(plan: tuple[CaseStudy, ...], names, full: bool = False) -> tuple[CaseStudy, ...]:
    """The case studies of ``names`` (all of ``plan`` when empty), in the order given: a built-in
    scene's from ``plan`` (:func:`smfem.studies.plan.select`), a scene file's made for it
    (:func:`study_of`, quick or ``full``)."""
    if not names:
        return plan
    return tuple(study_of(n, full) if is_scene_file(n) else select_builtin(plan, (n,))[0] for n in names)
