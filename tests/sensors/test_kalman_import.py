"""fearguard.sensors.kalman: filterpy's filters without scipy.stats (or scipy.ndimage, scipy.linalg) until a likelihood is asked
for, and the real modules for everyone else. Each check runs in a fresh interpreter (imports are process-wide)."""

from __future__ import annotations

import subprocess
import sys


def _run(code: str) -> list[str]:
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return out.split()


def test_a_fearguard_and_its_filters_do_not_import_scipy_stats_ndimage_or_linalg():
    probe = (
        "import sys, numpy as np, fearguard as fg\n"
        "g = fg.FearGuard(lambda f: 0.0)\n"
        "for k in range(3):\n"
        "    g.step(fg.Observation(0.1 * k, 1.0, np.full((120, 160, 3), k, np.uint8), ultrasonic_range_m=2.0 - 0.1 * k))\n"
        "print('filterpy.kalman' in sys.modules, 'scipy.stats' in sys.modules, 'filterpy.stats' in sys.modules,"
        " 'scipy.ndimage' in sys.modules, 'scipy.linalg' in sys.modules)"
    )
    assert _run(probe) == ["True", "False", "False", "False", "False"]


def test_process_noise_is_filterpys_block_matrix():
    probe = (
        "import numpy as np\n"
        "from fearguard.sensors.kalman import white_noise_q\n"
        "q = white_noise_q(dim=2, dt=0.05, var=0.7)\n"
        "from filterpy.common import Q_discrete_white_noise\n"
        "print(np.array_equal(q, Q_discrete_white_noise(dim=2, dt=0.05, var=0.7)))"
    )
    assert _run(probe) == ["True"]


def test_scipy_linalg_imported_after_is_the_real_module_and_filterpy_calls_it():
    probe = (
        "import sys, numpy as np\n"
        "from fearguard.sensors.kalman import kalman_filter\n"
        "kalman_filter(dim_x=2, dim_z=1)\n"
        "before = 'scipy.linalg' in sys.modules\n"
        "from filterpy.kalman import MerweScaledSigmaPoints\n"
        "sigmas = MerweScaledSigmaPoints(2, alpha=0.1, beta=2.0, kappa=1.0).sigma_points(np.zeros(2), np.diag([4.0, 1.0]))\n"
        "import scipy, scipy.linalg\n"
        "real = scipy.linalg is sys.modules['scipy.linalg'] and scipy.linalg.__file__.endswith('__init__.py')\n"
        "print(before, real, issubclass(scipy.linalg.LinAlgError, Exception), sigmas.shape, round(float(sigmas[1, 0]), 6))"
    )
    # sigma point 1 = mean + the first column of cholesky((n + lambda) P), lambda = alpha² (n + kappa) - n = -1.97
    assert _run(probe) == ["False", "True", "True", "(5,", "2)", str(round((0.03 * 4.0) ** 0.5, 6))]


def test_scipy_linalg_already_imported_is_what_filterpy_gets():
    probe = (
        "import sys, scipy.linalg\n"
        "from fearguard.sensors.kalman import kalman_filter\n"
        "kalman_filter(dim_x=2, dim_z=1)\n"
        "import filterpy.kalman.UKF as ukf\n"
        "print(ukf.cholesky is scipy.linalg.cholesky, sys.modules['scipy.linalg'] is scipy.linalg)"
    )
    assert _run(probe) == ["True", "True"]


def test_the_likelihood_is_filterpys_own_once_asked_for():
    probe = (
        "import sys, numpy as np\n"
        "from fearguard.sensors.kalman import kalman_filter, white_noise_q\n"
        "kf = kalman_filter(dim_x=2, dim_z=1)\n"
        "kf.x = np.array([[0.0], [1.0]]); kf.F = np.array([[1.0, 0.1], [0.0, 1.0]]); kf.H = np.array([[1.0, 0.0]])\n"
        "kf.P *= 4.0; kf.R *= 0.5; kf.Q = white_noise_q(dim=2, dt=0.1, var=1.0)\n"
        "kf.predict(); kf.update(np.array([[0.3]]))\n"
        "ll = kf.log_likelihood\n"
        "from scipy.stats import multivariate_normal\n"
        "S = kf.S; y = kf.y\n"
        "print(abs(ll - multivariate_normal.logpdf(y.ravel(), np.zeros(1), S)) < 1e-12, 'scipy.stats' in sys.modules)"
    )
    assert _run(probe) == ["True", "True"]


def test_filterpy_stats_imported_after_is_the_real_module():
    probe = (
        "from fearguard.sensors.kalman import kalman_filter\n"
        "kalman_filter(dim_x=2, dim_z=1)\n"
        "import sys, filterpy, filterpy.stats\n"
        "from filterpy.stats import gaussian\n"
        "print(filterpy.stats.__file__.endswith('__init__.py'), filterpy.stats is sys.modules['filterpy.stats'],"
        " round(float(gaussian(1.0, 2.0, 3.0)), 6))"
    )
    assert _run(probe) == ["True", "True", "0.19497"]  # N(1; mean 2, variance 3) = exp(-1/6) / sqrt(6π)


def test_filterpy_already_imported_is_used_as_it_is():
    probe = (
        "import sys, filterpy.kalman\n"
        "from fearguard.sensors.kalman import kalman_filter\n"
        "kf = kalman_filter(dim_x=4, dim_z=2)\n"
        "print(type(kf) is filterpy.kalman.KalmanFilter, kf.x.shape == (4, 1), 'scipy.stats' in sys.modules)"
    )
    assert _run(probe) == ["True", "True", "True"]


def test_discrete_bayes_waits_and_is_the_real_module_when_imported():
    probe = (
        "import sys\n"
        "from fearguard.sensors.kalman import kalman_filter\n"
        "kalman_filter(dim_x=2, dim_z=1)\n"
        "before = 'scipy.ndimage' in sys.modules or 'filterpy.discrete_bayes' in sys.modules\n"
        "import numpy as np, filterpy, filterpy.discrete_bayes as db\n"
        "p = db.normalize(np.array([1.0, 3.0]))\n"
        "print(before, db is sys.modules['filterpy.discrete_bayes'], hasattr(db, 'predict'), p.tolist() == [0.25, 0.75])"
    )
    assert _run(probe) == ["False", "True", "True", "True"]
