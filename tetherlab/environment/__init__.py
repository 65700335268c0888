"""Models of the space environment (magnetic field, atmosphere) used by the effects in forces/."""
