"""The worker processes: pebble's pools (``pool``), what a worker does for itself (``worker``), its catalog.

What a worker runs is the work layer's (``service.work``), the only caller of these pools.
"""
