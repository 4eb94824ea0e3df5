//! Newton mode of the inverse problem (issue 3): Newton on the discrete equations of Problem 2,
//! eq. (61), whose fixed point `inverse::solve_frame` seeks. Work in progress.
