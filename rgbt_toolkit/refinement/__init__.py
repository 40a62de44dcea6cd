"""Bounding-box refinement on the visible frame (JMMAC Sec. III-C), behind the pipeline's ``BoxRefiner`` protocol."""
