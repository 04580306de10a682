"""Training from CAD: the model library.

- :mod:`~psorr.library.models`: :class:`ModelLibrary`, its models (surface samples, primitive shape graph)
  and training;
- :mod:`~psorr.library.ppf`: oriented point-pair features and the hash table of model pairs;
- :mod:`~psorr.library.orr_table`: the ORR baseline's own table of dense model surface pairs;
- :mod:`~psorr.library.file_format`: the ``.npz`` file of trained models; :mod:`~psorr.library.cache`:
  the training cache;
- :mod:`~psorr.library.symmetries`: a model's near-symmetries, found once per model;
- :mod:`~psorr.library.sources`: what the command line's MODELS argument names.
"""

from psorr.library.models import Model, ModelLibrary, TrainParams

__all__ = ["Model", "ModelLibrary", "TrainParams"]
