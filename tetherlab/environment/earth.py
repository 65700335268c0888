"""Earth constants shared by the environment models."""

#: Earth's rotation rate (rad/s): WGS 84 (NIMA TR8350.2, 3rd ed., table 3.1), omega = 7292115e-11.
EARTH_ROTATION_RATE_RAD_S = 7.292115e-5
