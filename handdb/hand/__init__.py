"""The hand: skeleton topologies, anatomy and the kinematic hand model.

:mod:`handdb.hand.skeletons` reads the topologies of ``schemas/skeletons``;
:mod:`handdb.hand.layout` finds a skeleton's palm and finger chains;
:mod:`handdb.hand.anthropometry` holds published hand proportions;
:mod:`handdb.hand.model` is the kinematic hand model with its forward kinematics;
:mod:`handdb.hand.correspondence` maps joints between skeletons.
"""
