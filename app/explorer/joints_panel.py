"""The explorer's "Joints" group: passive-joint cones and leg interference (kinematics/joints.py).

:func:`build_joints_folder` creates the controls inside the Design tab; :class:`JointsControls`
reads them into a :class:`~kinematics.joints.Joints` (the core validates every value, with the same
message as the CLI, the REST API and links) and writes a state's joints back into them.

Controls: a checkbox and a half-angle slider per joint kind (U on the carriages, S on the
platform), the cone axes, the legs' diameter (0 = no interference test) and the clearance.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Literal, cast

import viser

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.joints import CONE_AXES, JOINT_RANGES, Joints

from .typed_values import hold_typed_values

#: Slider ranges (the number boxes accept the whole valid range of kinematics.joints).
CONE_SLIDER = (5.0, 90.0, 1.0)
DIAMETER_SLIDER = (0.0, 30.0, 0.5)
CLEARANCE_SLIDER = (0.0, 10.0, 0.5)
#: Half-angle shown when a cone is switched on for the first time.
DEFAULT_CONE = 45.0


@dataclasses.dataclass
class JointsControls:
    """Handles of the Joints group of one client."""

    u_on: Any
    u_angle: Any
    s_on: Any
    s_angle: Any
    axis: Any
    diameter: Any
    clearance: Any
    message: Any
    folder: Any = None  # the group itself (hidden while the selector shows another mechanism)

    def handles(self) -> tuple[Any, ...]:
        """Every input handle (for wiring ``on_update``)."""
        return (self.u_on, self.u_angle, self.s_on, self.s_angle, self.axis, self.diameter, self.clearance)

    def read(self) -> tuple[Joints | None, str | None]:
        """``(joints, None)`` from the controls, or ``(None, message)`` naming the bad field."""
        try:
            joints = Joints(theta_u=float(self.u_angle.value) if self.u_on.value else None,
                            theta_s=float(self.s_angle.value) if self.s_on.value else None,
                            cone_axis=cast(Literal["normal", "home"], str(self.axis.value)),  # checked by Joints
                            leg_diameter=float(self.diameter.value),
                            clearance=float(self.clearance.value))
        except ParameterError as exc:
            return None, str(exc)
        self.u_angle.disabled = not self.u_on.value
        self.s_angle.disabled = not self.s_on.value
        self.clearance.disabled = float(self.diameter.value) <= 0.0
        return joints, None

    def show(self, joints: Joints) -> None:
        """Put ``joints`` into the controls (the caller suppresses the resulting callbacks)."""
        self.u_on.value = joints.theta_u is not None
        self.u_angle.value = joints.theta_u if joints.theta_u is not None else DEFAULT_CONE
        self.u_angle.disabled = joints.theta_u is None
        self.s_on.value = joints.theta_s is not None
        self.s_angle.value = joints.theta_s if joints.theta_s is not None else DEFAULT_CONE
        self.s_angle.disabled = joints.theta_s is None
        self.axis.value = joints.cone_axis
        self.diameter.value = joints.leg_diameter
        self.clearance.value = joints.clearance
        self.clearance.disabled = joints.leg_diameter <= 0.0


def build_joints_folder(gui: viser.GuiApi, joints: Joints) -> JointsControls:
    """The Joints folder (collapsed unless ``joints`` sets something) showing ``joints``."""
    cone_text = JOINT_RANGES["theta_u"][3]
    with gui.add_folder("Joints (cones, leg interference)", expand_by_default=not joints.is_default) as folder:
        u_on = gui.add_checkbox("limit U joints", joints.theta_u is not None,
                                hint="each U joint (on a carriage) lets its leg tilt at most theta_U from its axis")
        u_angle = hold_typed_values(gui.add_slider(
            "theta_U (deg)", min=CONE_SLIDER[0], max=CONE_SLIDER[1], step=CONE_SLIDER[2],
            initial_value=joints.theta_u if joints.theta_u is not None else DEFAULT_CONE,
            disabled=joints.theta_u is None, hint=f"half-angle of every U joint's cone; valid range {cone_text}"))
        s_on = gui.add_checkbox("limit S joints", joints.theta_s is not None,
                                hint="each S joint (on the platform) lets its leg tilt at most theta_S from its axis")
        s_angle = hold_typed_values(gui.add_slider(
            "theta_S (deg)", min=CONE_SLIDER[0], max=CONE_SLIDER[1], step=CONE_SLIDER[2],
            initial_value=joints.theta_s if joints.theta_s is not None else DEFAULT_CONE,
            disabled=joints.theta_s is None, hint=f"half-angle of every S joint's cone; valid range {cone_text}"))
        axis = gui.add_dropdown("cone axis", CONE_AXES, initial_value=joints.cone_axis,
                                hint="normal: base normal (U) and platform normal (S); home: each leg's direction "
                                     "at the home pose (carriages mid-stroke, legs mid-length)")
        diameter = hold_typed_values(gui.add_slider(
            "leg diameter", min=DIAMETER_SLIDER[0], max=DIAMETER_SLIDER[1], step=DIAMETER_SLIDER[2],
            initial_value=joints.leg_diameter,
            hint="legs as capsules of this diameter; two legs may not come closer (0: no interference test); "
                 f"valid range {JOINT_RANGES['leg_diameter'][3]}"))
        clearance = hold_typed_values(gui.add_slider(
            "clearance", min=CLEARANCE_SLIDER[0], max=CLEARANCE_SLIDER[1], step=CLEARANCE_SLIDER[2],
            initial_value=joints.clearance, disabled=joints.leg_diameter <= 0.0,
            hint=f"extra distance required between two legs' capsules; valid range {JOINT_RANGES['clearance'][3]}"))
        message = gui.add_markdown("", visible=False)
    return JointsControls(u_on=u_on, u_angle=u_angle, s_on=s_on, s_angle=s_angle, axis=axis, diameter=diameter,
                          clearance=clearance, message=message, folder=folder)
