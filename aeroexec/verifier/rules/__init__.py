"""The catalog rules. Importing this package registers every rule in the registry."""

from aeroexec.verifier.rules import (  # noqa: F401  (registration on import)
    behavior_properties,
    capabilities,
    code,
    incompatibility,
    references,
    start_order,
)
