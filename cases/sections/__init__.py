"""Unstructured quad9 cross-section meshes made with gmsh: one script per section
(``python -m cases.sections.NAME``) and the ``NAME.msh`` file it writes, kept here so that
nothing needs gmsh at run time (README.md)."""
