//! Tests across the readers: precision far from the origin, the real files, inspect,
//! scene syntax and a seeded mutation test.
