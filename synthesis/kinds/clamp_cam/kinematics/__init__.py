"""The kind's own kinematics (floats and CasADi symbols alike)."""
