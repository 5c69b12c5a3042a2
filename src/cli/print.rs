//! `print!` and `println!` for the command files: std's, with every character that could
//! drive the terminal made visible ([`crate::render::terminal::terminal_safe`]), because
//! messages quote file contents, file names and titles that may hold escape sequences.
//! Declared first in `cli/mod.rs` (`#[macro_use]`), so they shadow std's in every command.

/// std's `print!`, with control characters made visible ([`terminal_safe`]).
macro_rules! print {
    ($($arg:tt)*) => {
        ::std::print!("{}", $crate::render::terminal::terminal_safe(&format!($($arg)*)))
    };
}

/// std's `println!`, with control characters made visible ([`terminal_safe`]).
macro_rules! println {
    () => { ::std::println!() };
    ($($arg:tt)*) => {
        ::std::println!("{}", $crate::render::terminal::terminal_safe(&format!($($arg)*)))
    };
}
