"""Image signal processing: raw sensor data to the camera's 8-bit output (DESIGN.md "camgen.isp")."""
