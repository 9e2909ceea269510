"""The mechanism model: planar and spatial multibody mechanisms with ideal and clearance joints,
written once (reduced.mechanism.engine) over the kinds of body (reduced.mechanism.planar,
reduced.mechanism.spatial) through what a body offers the joints (reduced.mechanism.bodies)."""
