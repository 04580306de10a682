"""The package list, the one packaging setting pyproject.toml cannot say (everything else is there).

psorr's package data lives in the repository's top-level ``assets/`` folder, installed as the
package ``psorr.assets`` (``package-dir`` in pyproject.toml). setuptools' package discovery only
finds packages inside their parent's folder, and pyproject.toml takes either discovery or a fixed
list, not both; so the discovered packages and ``psorr.assets`` are listed here, and a new
subpackage of psorr/ or sim/ needs no edit.
"""

from setuptools import find_packages, setup

setup(packages=[*find_packages(include=["psorr*", "sim*"]), "psorr.assets"])
