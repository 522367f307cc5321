"""The core's input and output: ``bag`` (ROS 1, ROS 2 and MCAP recordings read through rosbags) and ``bag_writer``,
``trajectory`` (stamped poses, TUM files), ``datasets`` (real files from public repositories, pinned and checked),
``kalibr_car`` (Kalibr's car cameras), ``outputs`` (output paths checked before work, files renamed into place),
``cache`` (the one cache folder and its key scheme) and ``fingerprint`` (the modules a cached result ran through).
"""
