"""aeroexec: the behavior management system of a drone's executive layer.

A deterministic executive core (behavior coordinator, behavior specialist, resource
manager, behavior base class) after the 2017 Aerostack design, with MCAP recording,
an offline catalog/mission verifier, replay/diff, a MAVLink bridge and Rerun views.
"""

__version__ = "0.1.0"
