"""Tracking evaluation that reproduces published RGB-T benchmark numbers (GTOT, RGBT234, RGBT210, LasHeR, VOT-RGBT)."""
