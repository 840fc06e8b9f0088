"""The known map: field walls and confirmed stations, as segments for ray
casting and as grids (occupancy, distance) for localisation and planning."""
from .field_map import FieldMap, station_footprint
from .grid import DistanceGrid, GridSpec
from .raycast import cast_rays, march_rays

__all__ = ["FieldMap", "station_footprint", "GridSpec", "DistanceGrid", "cast_rays", "march_rays"]
