"""The skin's mechanics: the linear stiffness-matrix form stepped exactly (:mod:`.linear`) or
by a sparse leapfrog for large skins (:mod:`.leapfrog`), and the true-length form
(:mod:`.geometric`)."""
