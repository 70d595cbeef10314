"""What the start-up calibration measured, and the model it gives the controller."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from leadthrough.friction.measured_level import MeasuredLevelError
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription

BoolArray = NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class Calibration:
    """What the calibration measured.

    Attributes:
        pose: Where it was measured [rad].
        gravity_error: ``G_model − G_true`` at ``pose`` [Nm].
        coulomb_error: ``τ_C,model − τ_C,true`` at ``pose`` [Nm].
        payload: Payload mass that explains the gravity error best [kg].
        bias: Gravity error left once the payload is modelled [Nm] (0 on a joint that
            did not slide both ways).
        friction_scale: True over modelled Coulomb level, per joint [–]; a refused
            calibration keeps what it read (1 where it read nothing), of which only the
            levels below the model's are used (:meth:`lowered`).
        accepted: Whether the result is plausible (nobody touched the arm).
        reason: Why it was refused ("" if accepted).
        measured: Joints whose Coulomb level was measured: they slid both ways at pace for
            long enough (:data:`~.run._MEASURED`). The others keep the model's level (scale 1);
            their gravity error counts as not known. One that did not slide both ways at
            all (stiction held it) keeps its gravity too (no error) and does not enter the
            payload fit.
        torque_offset: The measured motor torque minus the command it measures, averaged
            over the run, per joint [Nm]: an offset of the measurement, which the arm never
            felt; already added back to :attr:`gravity_error`. None: not read (no measured
            torque, or the run stopped early).
        coulomb_spread: How far a Coulomb reading may be off, per joint [Nm]: half the
            standard deviations of the paced readings up and down, combined (each
            stretch's reading counted once per sample; :func:`~.run._scatter`). A joint that
            sticks and jumps between stretches scatters them. On the YuMi's plants the
            momentum balance scatters little (no measured joint of seeds 1–48 above 5 % of
            its level), and reads the dry plants' levels 0.8 % off in the median and at
            most 5 % (``calibration_accuracy.py``, seeds 1–16; a stretch starts on the
            Stribeck curve, so mostly high): the stiction margin's 5 %, the least error of
            any level, bounds them at the pose. On the Panda's, whose 6 Hz tracking rang,
            stretches disagreed by up to ±25 % of a shoulder's level and the levels came out
            up to 14 % off (with two periods of delay up to 71 %; at 4 Hz within 8.8 %,
            ``calibration_accuracy.py --robot panda --seeds 16 --delay 2``). None: not
            known (0).
        predicted: Joints whose tracking took the state predicted for when their command
            acted (:attr:`CalibrationRun.predicted`). None: not known.
        payload_com: The payload's centre of mass in the flange frame [m], as far as the
            pose shows it: its component along gravity there is 0, unseen
            (:meth:`CalibrationRun.payload_body`). None: at the flange (no payload, or
            no moment that stood out).
    """

    pose: FloatArray
    gravity_error: FloatArray
    coulomb_error: FloatArray
    payload: float
    bias: FloatArray
    friction_scale: FloatArray
    accepted: bool
    reason: str = ""
    measured: BoolArray | None = None
    coulomb_spread: FloatArray | None = None
    torque_offset: FloatArray | None = None
    predicted: BoolArray | None = None
    payload_com: FloatArray | None = None

    def summary(self) -> str:
        """One line: what was measured, or why the calibration was refused.

        A refused one also names the levels it read below the model's (:meth:`lowered`).
        """
        if not self.accepted:
            lowered = self.lowered()
            low = ", ".join(f"joint {j + 1} {lowered[j]:.2f}×"
                            for j in np.flatnonzero(lowered < 1.0))  # fmt: skip
            if not low:
                return self.reason
            return (f"{self.reason}; guiding with the model, its friction error at least what "
                    f"the levels read below it show ({low})")  # fmt: skip
        scale = self.friction_scale[self.measured]
        offset = ""
        if self.torque_offset is not None:
            offset = f", measured torque offset up to {np.max(np.abs(self.torque_offset)):.3f} Nm"
        ahead = ""
        if self.predicted is not None and self.predicted.any():
            joints = ", ".join(str(j + 1) for j in np.flatnonzero(self.predicted))
            ahead = f", joint(s) {joints} tracked one period ahead"
        where = ""
        if self.payload_com is not None:
            where = " at ({:.3f}, {:.3f}, {:.3f}) m".format(*self.payload_com)
        return (f"calibrated: payload {self.payload:.2f} kg{where}, Coulomb levels "
                f"×{scale.min():.2f}–{scale.max():.2f} of the model, gravity bias up to "
                f"{np.max(np.abs(self.bias)):.3f} Nm{offset}{ahead}")  # fmt: skip

    def lowered(self) -> FloatArray:
        """Per joint, how far below the model's a refused calibration read a level [–].

        The readings' ``friction_scale`` clipped to [0, 1] on the joints measured, 1
        elsewhere. A refused run's readings are not taken as levels (:meth:`friction`
        keeps the model's), but a level the model overstates is the error that runs a
        released arm on: the estimate reads it as a push along the motion and the
        compensation pushes with it, while one it understates only makes guiding heavier.
        So a level read at ``r`` < 1 times the model's widens that joint's relative
        error to at least ``1 − r``: more friction margin, never less. A joint that ran
        faster than ``max_speed`` or more than four strokes off its motion under the
        calibration's own feed-forward (the model's friction among it; or a hand: the two
        cannot be told apart) counts as read at 0: none of its model's level is sure (error
        1: no compensation, the whole level as margin; a hand on the arm during the
        calibration costs that joint its compensation until the next one). On dry #1 of a
        family whose levels are 0.5–1.5 of the model's (its wrist 0.52×), the wrist jumped
        at 2.01 rad/s under the 6 Hz loop of before, and ran more than 60 mrad off the
        motion under the 4 Hz one; guided
        with the model's level and error, the released arm ran 1.25 rad (passive 3.1 rad).
        """
        if self.measured is None:
            return np.ones_like(self.friction_scale)
        return np.where(self.measured, np.clip(self.friction_scale, 0.0, 1.0), 1.0)

    def robot(self, nominal: RobotDescription) -> RobotDescription:
        """The description with the measured payload (at :attr:`payload_com`)."""
        if not self.accepted:
            return nominal
        com = np.zeros(3) if self.payload_com is None else self.payload_com
        return nominal.with_payload(self.payload, com)

    def friction(self, nominal: FrictionModel, accuracy: float | None = None) -> FrictionModel:
        """The friction model with the measured Coulomb levels.

        Args:
            nominal: The model before the calibration.
            accuracy: Relative error of the measured levels away from the pose [–]; the
                joints that slid then carry ``min(nominal error + reading error +
                |friction_scale − 1|, accuracy)``: the model's level along the travel,
                rescaled by one reading, is off by what the model's shape is, plus what the
                reading is (:attr:`coulomb_spread` over the level read), plus how far the
                reading moved it. One reading cannot tell a level that changed everywhere
                (the rescale is right elsewhere) from a model whose shape is off at the pose
                (an identified model read beyond the stroke it was fitted on: the rescale
                is then as wrong elsewhere as it moved the level; traced on a plant whose
                identified level, rescaled by 10 % at the pose, stood 16 % over the plant's
                inside the stroke against a stated 7 %). With ``min(nominal error,
                accuracy)``, before, an identified model's small error stood under a level
                the reading set (the observer's band covered 86–89 % of the moving samples on
                plants whose friction was identified first). None keeps the nominal errors.

        A refused calibration gives ``nominal`` back, its errors widened where it read a
        level below the model's (:meth:`lowered`).
        """
        if not self.accepted:  # the model's levels, with as much error as the readings show
            lowered = self.lowered()
            if np.all(lowered == 1.0):
                return nominal
            return dataclasses.replace(nominal, relative_error=np.maximum(
                nominal.relative_error, 1.0 - lowered))  # fmt: skip
        error = nominal.relative_error
        if accuracy is not None and self.measured is not None:
            moved = np.abs(self.friction_scale - 1.0)  # how far the reading moved the level
            reading = self.reading_error(nominal) + moved
            error = np.where(self.measured, np.minimum(error + reading, accuracy), error)
        return dataclasses.replace(nominal, coulomb=nominal.coulomb * self.friction_scale,
                                   relative_error=error)  # fmt: skip

    def reading_error(self, nominal: FrictionModel) -> FloatArray:
        """Each level's relative error at the pose: its readings' spread over it [–].

        :attr:`coulomb_spread` over the level read (``nominal``'s at the pose times
        :attr:`friction_scale`); zeros without a spread or where no level was read.
        """
        read = nominal.coulomb_level(self.pose) * self.friction_scale
        spread = np.zeros_like(read) if self.coulomb_spread is None else self.coulomb_spread
        return np.divide(spread, read, out=np.zeros_like(read), where=read > 0.0)

    def level_error(
        self, far: FloatArray, nominal: FrictionModel, slope: float | None, floor: float
    ) -> MeasuredLevelError | None:
        """How far the levels read here are off anywhere (None: nothing read, no slope).

        Args:
            far: The relative error each level carries anywhere [–] (the controller's
                after :meth:`friction`; also that of the joints not read).
            nominal: The friction model the readings rescaled.
            slope: ``CalibrationParameters.level_slope`` [1/rad].
            floor: The least relative error of any level [–] (the stiction margin).
        """
        if not self.accepted or self.measured is None or slope is None:
            return None
        at_pose = np.minimum(np.maximum(self.reading_error(nominal), floor), far)
        return MeasuredLevelError(self.pose.copy(), np.where(self.measured, at_pose, far),
                                  np.array(far, dtype=float), slope)  # fmt: skip


def implausible_friction(scale: FloatArray, max_change: float) -> BoolArray:
    """Where a measured Coulomb level, ``scale`` times the model's, is not plausible [–].

    Outside ``[1 / (1 + max_change), 1 + max_change]``: the errors a level must pass
    multiply, so the band is symmetric in the ratio's logarithm (a level 1.6× the model's
    is as plausible as one 1 / 1.6× of it). A ratio ≤ 0 (friction that pushes) is never.
    """
    limit = 1.0 + max_change
    return (scale > limit) | (scale < 1.0 / limit)


def gravity_share(bias: FloatArray, gravity: FloatArray, limit: float) -> FloatArray:
    """Per joint, the relative error of G that explains a gravity error read at a pose [–].

    ``bias`` = ``G_model − G_true`` and ``gravity`` = ``G_model`` at the calibration pose
    [Nm]. A drive that applies ``g`` times what it is told scales a joint's gravity torque
    rather than shifts it: the part of ``bias`` up to ``limit`` times ``|G|`` (the drives'
    gain tolerance, ``LeadThroughParameters.drive_gain_uncertainty``) is taken as ``k G``,
    which follows G away from the pose, and only the rest as a constant. A mass off does not
    scale each joint's G alike, so its share stays constant: with the masses' 5 % in the
    limit too (15 %), a mass error read on a wrist joint holding 0.4 Nm was taken as 14 % of
    its G, and a released arm with masses ±10 % coasted 0.56 s. A drive gain of 1.09 on
    a shoulder holding 5 Nm at the pose reads a bias of 0.4 Nm there, but is 0.03 Nm off
    where the shoulder holds 0.3 Nm: kept constant, the difference read as a push that ran a
    released arm on for 0.67 s (dry #59 stiff upwards of ``benchmarks/guiding_quality.py``).

    A bias larger than a gain can make at the pose (``|bias| > limit |G|``) is mostly
    something else, whose sign says nothing of the gain's: the share fades from ``±limit``
    there to 0 at twice that (``|bias| ≥ 2 limit |G|``, where what is not a gain must be
    at least as large as what a gain can be). Before, it stayed at ``±limit`` however large
    the bias: on an arm whose shoulder held 0.23 Nm at the pose (upright) and whose masses
    read it 0.13 Nm off, the share took 10 % of the shoulder's G the wrong way, the
    shoulder was held with 0.83 of its gravity half a radian down, and released arms sank
    up to 0.96 rad in either mode (a reviewer's six-joint arm, lugre #1 of the benchmark).
    """
    if limit <= 0.0:  # no drive gain error allowed: all of the bias stays constant
        return np.zeros_like(np.asarray(bias, dtype=float))
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(gravity != 0.0, bias / gravity, 0.0)
    beyond = np.abs(share) / limit  # how many gains' worth the bias is
    return np.clip(share, -limit, limit) * np.clip(2.0 - beyond, 0.0, 1.0)
