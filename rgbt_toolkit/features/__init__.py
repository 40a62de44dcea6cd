"""Feature extractors for the ECO tracker: fHOG, colour names, intensity, deep backbone layers."""

from rgbt_toolkit.features.base import BlockSpec, Feature

__all__ = ["BlockSpec", "Feature"]
