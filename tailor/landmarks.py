"""Names of the body landmarks that pattern placements and attachments may refer to.

A landmark is a horizontal cross-section of a standing body (torso and legs) or a cross-section
of a limb around its axis (arms). The body module finds them on any human mesh by slicing;
patterns refer to them by these names so one pattern dresses many bodies.
"""

__all__ = ["TORSO_LANDMARKS", "LIMB_LANDMARKS", "LANDMARKS"]

TORSO_LANDMARKS = ("neck", "shoulders", "armpits", "chest", "bust", "underbust", "waist", "hips", "crotch")
"""Cross-sections of the trunk, top to bottom (``bust`` is an alias of ``chest``; ``armpits`` is the
trunk's last cut below the arms, where an armhole's lowest point belongs)."""

LIMB_LANDMARKS = (
    "left_upper_arm", "right_upper_arm", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
    "left_thigh", "right_thigh", "left_knee", "right_knee", "left_ankle", "right_ankle",
)
"""Cross-sections of the limbs; arms are sliced across their own axis, legs horizontally."""

LANDMARKS = TORSO_LANDMARKS + LIMB_LANDMARKS
"""Every landmark name a pattern may use."""
