"""Stage 1 of the method: a camera frame made into a metric top view of the floor, as one remap table.

In the order the first paper builds it: ``cubemap`` (the fisheye's five virtual pinhole faces, eqs. 8-18), ``gpi``
(the ground plane image, eq. 22), ``ortho`` (the ortho-rectified GPI, from a chessboard of known size), and beside
them ``analytic`` (the same floor image from the calibration and the mount alone). ``image`` holds what they share:
``FloorImage`` (a floor patch in base_link, metres, and its pixels), ``RemapTable`` (camera pixel of each floor-image
pixel: one ``cv2.remap`` a frame) and the one default floor patch a run config leaves unset.
"""
