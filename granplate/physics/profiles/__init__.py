"""A drive's time profiles (docs/model.md section 3.11), one module each, named as the
profile (`-` written `_`), registered in setup.drive_profiles.DRIVE_PROFILE_REGISTRY. Each
gives one compiled function, `profile_terms(t, par, tab, n)`: (int_0^t P, P(t), P'(t),
P''(t)) at t >= 0 [s] from the drive's parameters par (the PAR_* columns below) and its
table tab[:n] (the TAB_* columns; read by the profile "table" only); physics.drives
dispatches on the profile's id, its position in the registry.
"""

from __future__ import annotations

#: columns of a drive's parameters: the Drive fields of setup.drive_profiles.PAR_FIELDS in
#: their order (value, amplitude, frequency [Hz], duration [s], the chirp's end frequency
#: [Hz]), then a force-driven wall's mass [kg] (a piston's; 0 otherwise)
PAR_VALUE, PAR_AMPLITUDE, PAR_FREQUENCY, PAR_DURATION, PAR_FREQUENCY_END, PAR_MASS = range(6)
N_PAR = 6
#: columns of a drive's table: the times [s], the values, the integral of the values from 0
TAB_T, TAB_V, TAB_I = range(3)
