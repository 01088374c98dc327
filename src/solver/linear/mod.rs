//! Projective dynamics' linear algebra: the sparse Cholesky factor of its constant global
//! matrix M + h²L ([`cholesky`], kept in faer's supernodal layout), the dense blocks of one
//! supernode and their substitutions ([`supernode`]), the elimination tree that splits the
//! substitutions over threads ([`etree`]), and the fill-reducing order ([`ordering`]).
//!
//! It knows matrices, not springs: it imports only the threads (`solver::threads`), and the
//! methods above build their matrices and call it.

pub(crate) mod cholesky;
pub(crate) mod etree;
pub(crate) mod ordering;
pub(crate) mod supernode;
