"""smfem: the semi-analytic finite element method (SMFEM) for bodies of revolution and prisms."""

__version__ = "0.1.0"
