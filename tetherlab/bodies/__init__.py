"""Body parts of the reaction solve: point bodies and rigid bodies with momentum wheels and
attitude control (paper section 2.5; docs/model.md section 12).

registry.py: the part types (kind code, name, module) and the part interface; parts.py: the
dispatcher generated from it (python -m tetherlab.model.dispatch); common.py: what every part
shares; point.py: the point body; rigid_body.py: the rigid body (its wheel set as a sub-part: wheels.py, motor torques
with their limits); rigid.py: quaternion kinematics, rotation matrices, gravity-gradient torque;
control.py: the quaternion-feedback PD law.  The tethers are tetherlab/tether/ (chain.py, the
rod chain; solve.py, the driver that iterates the parts in elimination order).
"""
