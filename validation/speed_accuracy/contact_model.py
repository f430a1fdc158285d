"""Contact law: Hertz-Mindlin or linear, each with the Coulomb and the LIGGGHTS tangential law.

    .venv/bin/python validation/speed_accuracy/contact_model.py

The shipped cases use Hertz-Mindlin with the default "impact" tangential law (Coulomb-capped,
calibrated to eps_t = 0.8 in one impact); the Coulomb law here takes k_t, gamma_t calibrated to
eps_t = 0.8 (``dem calibrate``). Every law runs at 0.82 of its own stability limit, as the
base does. The linear law takes the k_n whose
contact time equals the Hertz contact time of a grain landing on the floor at the drive speed
A omega (so the two laws resolve the same impact in about the same number of steps); under the
Coulomb law its k_t and gamma_t are derived from eps_t = 0.8, under the LIGGGHTS law
k_t / k_n = 2/7. The LIGGGHTS law with Hertz takes Mindlin's k_t, as a LIGGGHTS deck does.
"""

from study import BASE_TIMESTEP_FRACTION, CASES, FILL_SEEDS, Point, default_points, load, main

from dem.run import accuracy


def linear_stiffness(case_name: str) -> float:
    """k_n, N/m (3 digits), with the contact time of a Hertz grain-floor impact at A omega."""
    case = load(Point("contact_model", case_name, "base", "base"))
    return float(f"{accuracy.linear_equivalent_stiffness(case):.3g}")


def points(case_name: str) -> list[Point]:
    k = linear_stiffness(case_name)
    f = BASE_TIMESTEP_FRACTION
    linear = {"contact.model": "linear", "contact.youngs_modulus": None,
              "contact.stiffness": k, "contact.tangential_stiffness_ratio": None,
              "contact.tangential_damping_ratio": None}  # fmt: skip
    liggghts = {"contact.tangential": "liggghts", "contact.tangential_stiffness_ratio": None,
                "contact.tangential_damping_ratio": None}  # fmt: skip
    return default_points("contact_model", case_name, FILL_SEEDS[case_name]) + [
        Point("contact_model", case_name, "Hertz, Coulomb tangential", "hertz coulomb",
              {"contact.tangential": "coulomb"}, timestep_fraction=f),
        Point("contact_model", case_name, "Hertz, LIGGGHTS tangential", "hertz liggghts",
              liggghts, timestep_fraction=f),
        Point("contact_model", case_name, f"linear {k:.3g} N/m, impact", "linear impact",
              linear, timestep_fraction=f),
        Point("contact_model", case_name, f"linear {k:.3g} N/m, Coulomb", "linear coulomb",
              linear | {"contact.tangential": "coulomb"}, timestep_fraction=f),
        Point("contact_model", case_name, f"linear {k:.3g} N/m, LIGGGHTS", "linear liggghts",
              linear | {"contact.tangential": "liggghts"}, timestep_fraction=f),
    ]  # fmt: skip


POINTS = [p for case in CASES for p in points(case)]

if __name__ == "__main__":
    raise SystemExit(main("contact_model", POINTS, "contact law and tangential law", __file__))
