"""Models built from the spec: the URDF, pinocchio dynamics (static torques, the multibody ZMP), the MX-28 servo model
and the compliant-servo equilibrium (where a pose sags, how the load splits between the feet)."""
