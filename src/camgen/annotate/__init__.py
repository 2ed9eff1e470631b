"""Annotations computed from the scene geometry and the instance pass, through the same lens model as
the pixels (boxes, masks, visibility, tracks)."""
