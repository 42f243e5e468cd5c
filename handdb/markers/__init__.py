"""Marker fitting: 3D marker clips calibrated and fitted with the kinematic hand model.

The method of Zhao, Chai & Xu (SCA 2012): the subject's bone lengths are calibrated from the
clip (:mod:`handdb.markers.calibration`), then the 33-DoF hand model
(:mod:`handdb.hand.model`) is fitted to every frame's markers (:mod:`handdb.markers.solve`:
robust marker term, smoothness, particle swarm or least squares), and
:mod:`handdb.markers.fit` ties both into :func:`~handdb.markers.fit.fit_markers`, the stage
the build runs. :mod:`handdb.markers.tables` writes the ``markers_3d`` rows.
"""

#: Version of the marker fit. Raise it when a change alters the output; it
#: enters the build keys (:mod:`handdb.build.keys`), a docstring edit or a speed-up does not.
VERSION = 2
