"""Coverage of a camera network on a ground grid: where each camera sees a person, at what pixel
density, and at which IEC 62676-4 DORI class; the network's figures and a layout optimiser.

Every point goes through the same lens model as the pixels (`camgen.optics.projection`, distortion
included) and is tested for occlusion against the scene's environment meshes. Cameras are built as
`camgen.plan` builds them (profile camera matrix, the lens at its focal length, mount and head pose).
"""
