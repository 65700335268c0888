"""Rigid bodies with momentum wheels and attitude control (paper section 2.5).

rigid.py: quaternion kinematics, rotation matrices, Euler's equations' terms, gravity-gradient
torque; wheels.py: motor torques with their limits; control.py: the quaternion-feedback PD law.
The elimination that couples them to the tethers is in tetherlab/tether/chain.py; the derivation
in docs/model.md section 12.
"""
