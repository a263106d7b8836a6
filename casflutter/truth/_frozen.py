"""The truth with its aerodynamics frozen at one speed: what a V²-scaled ROM represents.

ΣAE of a ROM identified at ``V0`` (paper eq. 8) feeds the structure ``alpha V^2 y`` with
``y`` the aerodynamic operator identified at ``V0``: only the dynamic pressure is scaled.
The aerodynamic operator itself depends on V through its time scale ``b / U``:
apparent-mass forces scale with ``U^0``, aerodynamic damping with ``U^1``, the Wagner lag
rates with ``U`` (a frequency ``omega`` has the reduced frequency ``k = omega b / U``).  The
V² scaling freezes all of them at their ``V0`` values, so such a ΣAE(V) is exactly the truth
with its aerodynamics frozen at ``V0`` and scaled by ``(V / V0)^2``; its flutter speed
differs from the truth's by the V²-scaling error.  Static divergence is exact under the V²
scaling: the steady aerodynamic stiffness (``omega = 0``) does not depend on the time scale.
"""

from __future__ import annotations

from dataclasses import replace

__all__ = ["frozen_aero_truth"]


def frozen_aero_truth(truth, V0: float):
    """The truth with its aerodynamics frozen at ``V0`` and scaled by ``(V / V0)^2``.

    Built from the truth's own aerodynamic matrices, independently of any identification
    (module docstring).

    Parameters
    ----------
    truth : AeroelasticTruth
        The simulator.
    V0 : float
        Speed index at which the aerodynamics are frozen.

    Returns
    -------
    AeroelasticTruth
        Same class and parameters; ``aero_matrices(V)`` is ``aero_matrices(V0)`` with every
        force matrix times ``(V / V0)^2`` and the lag rates of ``V0``.

    See Also
    --------
    find_flutter : the flutter speed of the truth and of its frozen copy.

    Examples
    --------
    >>> import casflutter as cf
    >>> truth = cf.load_problem("typical_section")
    >>> frozen = cf.frozen_aero_truth(truth, 1.8)
    >>> round(cf.find_flutter(truth, (0.5, 3.0)).Vf, 3), round(cf.find_flutter(frozen, (0.5, 3.0)).Vf, 3)
    (2.17, 2.259)
    """
    base = type(truth)
    V0 = float(V0)

    class _Frozen(base):
        def aero_matrices(self, V):
            am = base.aero_matrices(self, V0)
            s = (float(V) / V0) ** 2
            return replace(am, Kx=s * am.Kx, Cx=s * am.Cx, Mx=s * am.Mx, Fv=s * am.Fv,
                           Fv1=s * am.Fv1, Fv2=s * am.Fv2, W=s * am.W)

    _Frozen.__name__ = f"Frozen{base.__name__}"
    return _Frozen(truth.params)
