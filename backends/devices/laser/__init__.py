"""Laser scanners: :class:`~.urg.UrgLaser` (Hokuyo URG, SCIP 2.0 over USB
serial) and :class:`~.tim.TimLaser` (SICK TiM5xx, CoLa-A or CoLa-B over
TCP), both :class:`~.base.LaserDriver`; the device sides for emulators are
:mod:`.urg_device` and :mod:`.tim_device`."""
from .base import LaserDriver, LaserMount, LaserStats, LinkLost

__all__ = ["LaserDriver", "LaserMount", "LaserStats", "LinkLost"]
