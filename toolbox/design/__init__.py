"""Design methods: each turns a validated spec into a ControllerArtifact."""

from ._registry import METHOD_MODULES, design, read_method_cfg

__all__ = ["METHOD_MODULES", "design", "read_method_cfg"]
