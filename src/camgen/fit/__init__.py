"""Profiles from real hardware: noise from raw frames, lens intrinsics from boards, reference matching."""
