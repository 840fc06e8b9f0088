"""Exploring zones and turning camera detections into machine observations."""
from .explore import ExploreZone, order_viewpoints, ring_viewpoints
from .sightings import SightingCollector

__all__ = ["ExploreZone", "SightingCollector", "ring_viewpoints", "order_viewpoints"]
