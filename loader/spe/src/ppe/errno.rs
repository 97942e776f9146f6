//! The errno values a call returns, as the SPU's newlib defines them (`sys/errno.h` of
//! newlib's SPU port, which uses Linux's numbers so that libspe2's handlers can pass the
//! PPE's errno straight through).

/// Operation not permitted.
pub const EPERM: i32 = 1;
/// No such file or directory.
pub const ENOENT: i32 = 2;
/// Input/output error.
pub const EIO: i32 = 5;
/// Bad file descriptor.
pub const EBADF: i32 = 9;
/// Permission denied.
pub const EACCES: i32 = 13;
/// Invalid argument.
pub const EINVAL: i32 = 22;
/// Too many open files.
pub const EMFILE: i32 = 24;
/// Illegal seek.
pub const ESPIPE: i32 = 29;
/// Function not implemented.
pub const ENOSYS: i32 = 38;
/// Value too large for its type.
pub const EOVERFLOW: i32 = 75;
