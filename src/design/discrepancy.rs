//! The centred L2 discrepancy of a point set (Hickernell 1998).
