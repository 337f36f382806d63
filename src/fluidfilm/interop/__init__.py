"""Bridges to other codes. ``fluidfilm.interop.ross``: fluidfilm force models as ROSS bearing elements
(``FluidFilmBearingElement``) and as the nonlinear bearings of a ROSS rotor (``pip install "fluidfilm[ross]"``;
ROSS 3.1 needs Python >= 3.13; in the workspace, ``make ross-env`` builds such an environment). Nothing else in fluidfilm imports ROSS, and this package imports it only when it is used."""

__all__: list[str] = []
