//! The errno values a call returns, as the SPU's newlib defines them (`sys/errno.h` of
//! newlib's SPU port, which uses Linux's numbers so that libspe2's handlers can pass the
//! PPE's errno straight through).

pub const EPERM: i32 = 1;
pub const ENOENT: i32 = 2;
pub const EIO: i32 = 5;
pub const EBADF: i32 = 9;
pub const EACCES: i32 = 13;
pub const EINVAL: i32 = 22;
pub const EMFILE: i32 = 24;
pub const ESPIPE: i32 = 29;
pub const ENOSYS: i32 = 38;
pub const EOVERFLOW: i32 = 75;
