"""Checks of what the library is given, each failure an :class:`~psorr.errors.InvalidInputError` that names
the value and the fix: arrays (:mod:`~psorr.checks.arrays`), settings objects' fields
(:mod:`~psorr.checks.params`) and clouds' units and frames (:mod:`~psorr.checks.clouds`)."""
