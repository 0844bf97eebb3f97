"""The enriched basis and the Fermi–Pasta–Ulam system from Python: the same map as a fine
polynomial run (`gvi run fpu --basis enriched --omega 50 --n 7 --h 0.025 --steps 40` lies
6.7e-16 from `--basis legendre --n 20` at every step end), the oscillatory energies as
invariants, and typed errors for a missing or bad ω."""

import numpy as np
import pytest

import galerkin_vi as gv

OMEGA = 50.0
# Hairer–Lubich–Wanner's start (GNI §I.5): q1 = 1, p1 = 1, q4 = 1/ω, p4 = 1.
Q0 = [1.0, 0.0, 0.0, 1.0 / OMEGA, 0.0, 0.0]
P0 = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0]


def test_enriched_fpu_is_the_fine_polynomial_map():
    fpu = gv.systems.Fpu(springs=3, omega=OMEGA)
    enriched = gv.Integrator(basis="enriched", n=7, h=0.025, omega=OMEGA).integrate(fpu, Q0, P0, 40)
    fine = gv.Integrator(basis="legendre", n=20, h=0.025).integrate(fpu, Q0, P0, 40)
    # Measured 6.7e-16 through the CLI; 1e-12 leaves room for another machine's round-off.
    assert np.abs(enriched.q - fine.q).max() < 1e-12
    assert np.abs(enriched.p - fine.p).max() < 1e-12
    # A coarse polynomial run at the same h is not that map: the comparison can fail.
    coarse = gv.Integrator(basis="legendre", n=3, h=0.025).integrate(fpu, Q0, P0, 40)
    assert np.abs(coarse.q - fine.q).max() > 1e-6


def test_fpu_reports_its_oscillatory_energies():
    fpu = gv.systems.Fpu()
    traj = gv.Integrator(basis="enriched", n=7, h=0.025, omega=OMEGA).integrate(fpu, Q0, P0, 40)
    inv = traj.invariants
    assert {"energy", "oscillatory_energy", "I1", "I2", "I3"} <= set(inv)
    total = inv["I1"] + inv["I2"] + inv["I3"]
    np.testing.assert_allclose(inv["oscillatory_energy"], total, rtol=1e-14)
    # I(0) = ½(p4² + ω² q4²) = 1.
    assert inv["oscillatory_energy"][0] == pytest.approx(1.0, rel=1e-14)


@pytest.mark.parametrize("omega", [-1.0, 0.0, float("nan"), float("inf")])
def test_bad_omega_is_a_typed_error(omega):
    with pytest.raises(gv.GalerkinError):
        gv.Integrator(basis="enriched", n=7, h=0.025, omega=omega)


def test_enriched_without_omega_is_a_typed_error():
    with pytest.raises(gv.GalerkinError):
        gv.Integrator(basis="enriched", n=7, h=0.025)


def test_several_frequencies_from_a_list():
    # omega=[50, 20]: sin/cos of both in the space (n = 9 is p = 4). On the book's chain at
    # h = 0.025 both bases resolve the motion: the two-frequency map is the fine polynomial map
    # (same tolerance as the single-frequency test above).
    fpu = gv.systems.Fpu(springs=3, omega=OMEGA)
    two = gv.Integrator(basis="enriched", n=9, h=0.025, omega=[OMEGA, 20.0]).integrate(fpu, Q0, P0, 40)
    fine = gv.Integrator(basis="legendre", n=20, h=0.025).integrate(fpu, Q0, P0, 40)
    assert np.abs(two.q - fine.q).max() < 1e-12


@pytest.mark.parametrize("omega", [[], [OMEGA, OMEGA], [OMEGA, float("nan")], [OMEGA, -20.0]])
def test_bad_frequency_lists_are_typed_errors(omega):
    # Empty, equal (nearly degenerate: refused, not merged), not finite, not positive.
    with pytest.raises(gv.GalerkinError):
        gv.Integrator(basis="enriched", n=9, h=0.025, omega=omega)
