"""The mechanism model: planar and spatial multibody mechanisms with ideal and clearance joints:
their scenes, the build into the arrays of the compiled core's engine (reduced.mechanism.kernel,
cpp/mechanism/), the kinds of body (reduced.mechanism.planar, .spatial) and the outputs."""
