//! ICE verification studies (placeholder while building).
