"""Model layer: a scenario turned into the flat arrays the solver takes."""

from granplate.model.arrays import Model, build_model  # noqa: F401
