//! What the protocol needs of a message layer (`Transport`): byte messages between numbered
//! ranks that never block, so that every wait above it has a time limit. MPI provides it in
//! production (libglray_mpi, over glray's own duplicate of MPI_COMM_WORLD); `memory` provides it
//! between threads, for tests of the protocol without MPI.

/// Ranks exchanging byte messages, sends and receives never blocking.
pub trait Transport {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    /// Starts sending `bytes` to rank `to`; the transport keeps them until they are gone.
    fn send(&mut self, to: usize, bytes: Vec<u8>) -> Result<(), String>;
    /// A message that has arrived (its sender and bytes), if any.
    fn poll(&mut self) -> Result<Option<(usize, Vec<u8>)>, String>;
    /// Whether every send started has completed (moving them on).
    fn flushed(&mut self) -> Result<bool, String>;
    /// Bytes of the sends started and not completed (moving them on): how far the network is
    /// behind. None here by default: a transport that hands bytes over at once.
    fn unsent(&mut self) -> Result<u64, String> {
        Ok(0)
    }
}

/// Ranks as threads of one process, for tests: each rank's inbox a channel.
pub mod memory {
    use std::sync::mpsc::{channel, Receiver, Sender};

    pub struct MemoryTransport {
        rank: usize,
        peers: Vec<Sender<(usize, Vec<u8>)>>,
        inbox: Receiver<(usize, Vec<u8>)>,
        /// Bytes sent and received, for tests of what crosses.
        pub sent: u64,
    }

    impl MemoryTransport {
        /// `size` connected ranks.
        pub fn group(size: usize) -> Vec<MemoryTransport> {
            let (senders, receivers): (Vec<_>, Vec<_>) = (0..size).map(|_| channel()).unzip();
            receivers
                .into_iter()
                .enumerate()
                .map(|(rank, inbox)| MemoryTransport { rank, peers: senders.clone(), inbox, sent: 0 })
                .collect()
        }
    }

    impl super::Transport for MemoryTransport {
        fn rank(&self) -> usize {
            self.rank
        }
        fn size(&self) -> usize {
            self.peers.len()
        }
        fn send(&mut self, to: usize, bytes: Vec<u8>) -> Result<(), String> {
            self.sent += bytes.len() as u64;
            // A rank gone (its thread ended) is as silent as a dead process: the waits time out.
            let _ = self.peers[to].send((self.rank, bytes));
            Ok(())
        }
        fn poll(&mut self) -> Result<Option<(usize, Vec<u8>)>, String> {
            Ok(self.inbox.try_recv().ok())
        }
        fn flushed(&mut self) -> Result<bool, String> {
            Ok(true)
        }
    }
}
