//! Writing results to disk atomically: PNG, NPY, JSON.
