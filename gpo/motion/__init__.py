"""Stage 2 of the method: how the floor moved between two frames, in floor-image pixels (u right, v down).

``klt`` (the first paper: KLT tracks over the floor image, their median motion vector and each frame's quality or
its flag), ``layers`` (a glossy floor's reflections told from the floor's own tracks) and ``keypoints`` (the second
paper: keypoints, matches, the histogram filter and the geometric invariance check).
"""
