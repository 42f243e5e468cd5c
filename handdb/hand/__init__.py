"""The hand: one place for its topology, anatomy, shape and motion.

* :mod:`handdb.hand.skeletons`: the topologies of ``schemas/skeletons`` (joints, bones,
  fingers, roles);
* :mod:`handdb.hand.layout`: a skeleton's palm and finger chains;
* :mod:`handdb.hand.anatomy`: joint ranges of motion, the DIP-PIP coupling, proportions
  and the mean palm, each with its source;
* :mod:`handdb.hand.shape`: a hand at rest (:class:`~handdb.hand.shape.HandShape`);
* :mod:`handdb.hand.population`: hands drawn as varied as real ones and their annotations;
* :mod:`handdb.hand.model`: the 33-degree-of-freedom kinematic model and its forward
  kinematics, on any skeleton.
"""
