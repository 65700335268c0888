"""The constant model of a scene, apart from the compiled kernels that run it.

What a scene becomes once it is loaded: its graph (oriented tethers, roots, elimination order), the
layout of its state vector, and the typed view of the parameter block the kernels read.  Nothing
here runs per right-hand-side call.
"""
