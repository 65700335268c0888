"""Body parts of the reaction solve: point bodies and rigid bodies with momentum wheels and
attitude control (paper section 2.5; docs/model.md section 12).

parts.py: the registry, every part function dispatched on the body's part kind; point.py: the
point body; rigid_body.py: the rigid body (its wheel set as a sub-part: wheels.py, motor torques
with their limits); rigid.py: quaternion kinematics, rotation matrices, gravity-gradient torque;
control.py: the quaternion-feedback PD law.  The tethers are tetherlab/tether/ (chain.py, the
rod chain; solve.py, the driver that iterates the parts in elimination order).
"""
