"""Input handling (Fig. 2: the inputs): ROS message definitions, test cases and their
encoding, the mapping from a message to a call, safe paths."""
