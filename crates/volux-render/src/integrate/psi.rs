//! Partial pre-integration (Moreland and Angel) and the Shirley-Tuchman average colour for cell projection (work in progress).
